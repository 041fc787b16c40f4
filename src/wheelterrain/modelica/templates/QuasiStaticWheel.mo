block QuasiStaticWheel "A wheel at steady state on the soil: the sinkage at which the static normal force carries the load"
  parameter Real p[${N}] = WheelTerrain.Data.rashidPatch
    "the parameters in table order (WheelTerrain.Data, Records.parameterVector)";
  parameter Real sinkage_start(unit="m") = 0.01
    "where the tool's solver starts looking for the sinkage";
  replaceable function quasiStaticFunction = WheelTerrain.Functions.quasiStatic
    constrainedby WheelTerrain.Functions.Interfaces.QuasiStatic
    "the contact: Functions.quasiStatic (generated, the default) or Functions.External.quasiStatic (CasADi's C)";
  input Real load(unit="N") "the vertical load on the wheel";
  input Real slip(unit="1") "the model's slip: traction i driving, skid s braking (-1 locked)";
  input Real slip_angle(unit="rad")
    "between the wheel's heading and its velocity, + moving toward its left (0: driven straight)";
  input Real turn_slip(unit="rad/m")
    "the wheel's yaw rate over its forward speed, + counter-clockwise from above (0: it does not yaw), |turn_slip| <= ${TURN_SLIP_LIMIT}";
  output Real sinkage(unit="m", start=sinkage_start, fixed=false)
    "the steady sinkage: the static normal force equals the load";
  output Real drawbar_pull(unit="N") "the net forward force of the soil on the wheel";
  output Real torque(unit="N.m") "the torque the soil resists the wheel's turning with";
  output Real entry_angle(unit="rad") "where the contact begins";
  output Real exit_angle(unit="rad") "where it ends";
  output Real lateral_force(unit="N") "the soil's force on the wheel along its axle, + to its left";
  output Real aligning_moment(unit="N.m") "the lateral stresses' moment about the vertical through the centre, + counter-clockwise from above";
  output Real turning_moment(unit="N.m") "the soil's whole moment about that vertical (M_z): aligning_moment and the longitudinal shear's across the width";
  output Real overturning_moment(unit="N.m") "the lateral stresses' moment about the heading axis x through the centre (M_x), + by the right-hand rule";
  output Real y[${QUASI_ROWS}] "every output of quasiStatic, Functions.Index order";
  output Real y_lateral[${LATERAL_ROWS}] "every output of Functions.lateral, Functions.Index.Lateral order";
equation
  y = quasiStaticFunction(sinkage, slip, p);
  y[WheelTerrain.Functions.Index.normal_force_static] = load;
  drawbar_pull = y[WheelTerrain.Functions.Index.drawbar_pull];
  torque = y[WheelTerrain.Functions.Index.torque];
  entry_angle = y[WheelTerrain.Functions.Index.entry_angle];
  exit_angle = y[WheelTerrain.Functions.Index.exit_angle];
  assert(abs(turn_slip) <= ${TURN_SLIP_LIMIT}, "QuasiStaticWheel: |turn_slip| beyond ${TURN_SLIP_LIMIT} rad/m, the lateral contact's range");
  y_lateral = WheelTerrain.Functions.lateral(sinkage, slip, slip_angle, turn_slip, p);
  lateral_force = y_lateral[WheelTerrain.Functions.Index.Lateral.lateral_force];
  aligning_moment = y_lateral[WheelTerrain.Functions.Index.Lateral.aligning_moment];
  turning_moment = y_lateral[WheelTerrain.Functions.Index.Lateral.turning_moment];
  overturning_moment = y_lateral[WheelTerrain.Functions.Index.Lateral.overturning_moment];
  annotation(Documentation(info="<html><p>The quasi-static wheel of <code>wheelterrain steady</code>: an implicit equation for the sinkage, solved by the tool. The contact is ripple-free with no sinkage rate and no memory. At a slip angle and a turn slip the lateral force and the moments are Functions.lateral's (Ishigami et al. 2007's side force, the turn slip's brush kinematics); the longitudinal outputs do not change with them.</p></html>"));
end QuasiStaticWheel;
