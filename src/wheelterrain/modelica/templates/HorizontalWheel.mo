model HorizontalWheel "A rigid wheel with grousers seen from above: PlanarMechanics' plane is the ground, the wheel's load an input; drawbar pull, lateral force and turning moment act in the plane"
  import SI = Modelica.Units.SI;
  replaceable parameter WheelTerrain.Records.Presets.RashidPatch parameters
    constrainedby WheelTerrain.Records.Parameters "the wheel, the soil and the contact model (a preset)"
    annotation(choicesAllMatching=true);
  parameter Real r[2] = {1, 0} "the wheel's heading (its rolling direction) at frame_a.phi = 0";
  parameter SI.Length sinkage_start = 0.01 "where the tool's solver starts looking for the sinkage"
    annotation(Dialog(tab="Advanced"));
  PlanarMechanics.Interfaces.Frame_a frame_a
    "the hub in the ground plane: x, y on the ground, phi the heading's yaw, counter-clockwise from above"
    annotation(Placement(transformation(extent={{-116,-16},{-84,16}})));
  Modelica.Mechanics.Rotational.Interfaces.Flange_a flange_a
    "the axle: the wheel's spin, positive rolling along r (the drive's reaction is about the axle, out of this plane)"
    annotation(Placement(transformation(extent={{90,-10},{110,10}})));
  Modelica.Blocks.Interfaces.RealInput load(unit="N") "the vertical load the wheel carries (> 0)"
    annotation(Placement(transformation(extent={{-20,-20},{20,20}}, rotation=90, origin={0,-120})));
  final parameter Real p[${N}] = WheelTerrain.Records.parameterVector(parameters) "the parameters in table order";
  final parameter Real e[2] = r/sqrt(r*r) "the heading at phi = 0, a unit vector";
  Real heading[2] "the heading in the ground plane";
  SI.Velocity v[2] "the hub's velocity";
  SI.Velocity v_long "along the heading";
  SI.Velocity v_lat "across it, + toward the wheel's left";
  SI.AngularVelocity wheel_speed "the wheel's spin, + rolling along the heading";
  SI.AngularVelocity yaw_rate "the heading's yaw rate";
  Real rolling(unit="1") "-1 rolling backward (omega*R + v < 0: both speeds <= 0 but near rest): the mirror image of rolling forward; else 1";
  Real slip(unit="1") "the model's slip along the rolling: traction driving, skid braking (-1 locked)";
  SI.Angle slip_angle "the contact's: atan2(v_lat, |v_long|), + moving toward its left";
  Real turn_slip(unit="rad/m") "the contact's: the yaw rate over the speed, mirrored rolling backward";
  SI.Force drawbar_pull "the soil's force on the wheel along the heading";
  SI.Force lateral_force "the soil's force on the wheel across the heading, + to its left";
  SI.Torque turning_moment "the soil's moment on the wheel about the vertical, + counter-clockwise from above";
  SI.Torque torque "the torque the soil resists the wheel's rolling with (the axle carries it)";
  SI.Torque overturning_moment "about the heading, out of this plane (not applied)";
  SI.Length sinkage "the steady sinkage at the load";
  Real share(unit="1")
    "the direction of rolling's share of the contact: 1, but within the slip's speed floor of the turn of rolling, where the wheel rolling the other way takes the rest (Functions.turningWeight, the FMU's blend)";
  WheelTerrain.Components.QuasiStaticWheel contact(p=p, sinkage_start=sinkage_start, load=load, slip=slip,
    slip_angle=slip_angle, turn_slip=turn_slip) "the quasi-static contact of the steady state (wheelterrain steady)"
    annotation(Placement(transformation(extent={{-20,-60},{20,-20}})));
  WheelTerrain.Components.QuasiStaticWheel contact_turned(p=p, sinkage_start=sinkage_start, load=load, slip=-slip,
    slip_angle=-slip_angle, turn_slip=-turn_slip)
    "the wheel rolling the other way, the mirror image (weighted 1 - share: nothing outside the slip's speed floor of the turn of rolling)"
    annotation(Placement(transformation(extent={{-20,-100},{20,-60}})));
equation
  heading = {cos(frame_a.phi)*e[1] - sin(frame_a.phi)*e[2], sin(frame_a.phi)*e[1] + cos(frame_a.phi)*e[2]};
  v = {der(frame_a.x), der(frame_a.y)};
  v_long = v*heading;
  v_lat = -v[1]*heading[2] + v[2]*heading[1];
  wheel_speed = der(flange_a.phi);
  yaw_rate = der(frame_a.phi);
  // an equation, not a binding (as PartialWheel: rumoca 0.10 miscounts a binding's call here)
  rolling = WheelTerrain.Functions.rollingSign(wheel_speed, v_long, p);
  slip = WheelTerrain.Functions.slipFromSpeeds(rolling*wheel_speed, rolling*v_long, p);
  assert(slip >= -1 and slip <= 1, "HorizontalWheel: the slip left the model's range [-1, 1] (the wheel turning against its hub's motion beyond ${SLIP_SPEED_FLOOR} m/s of rest: |omega*R_ref| + |v|)");
  assert(load > 0, "HorizontalWheel: the load must be positive (a wheel off the ground has no contact)");
  slip_angle = atan2(v_lat, abs(v_long));
  assert(abs(slip_angle) <= ${SLIP_ANGLE_LIMIT}, "HorizontalWheel: |slip angle| beyond ${SLIP_ANGLE_DEG} deg, the lateral contact's range (a wheel moving sideways has no heading to slip along)");
  assert(abs(yaw_rate) <= ${TURN_SLIP_LIMIT}*max(rolling*v_long, 0), "HorizontalWheel: |yaw_rate|/speed beyond ${TURN_SLIP_LIMIT} rad/m, the lateral contact's range (a wheel yawing on the spot or at rest is outside the model)");
  turn_slip = if abs(yaw_rate) > 0 then rolling*yaw_rate/max(rolling*v_long, ${SPEED_FLOOR}) else 0;
  share = noEvent(if rolling > 0 then WheelTerrain.Functions.turningWeight(wheel_speed, v_long, p)
    else 1 - WheelTerrain.Functions.turningWeight(wheel_speed, v_long, p));
  sinkage = share*contact.sinkage + (1 - share)*contact_turned.sinkage;
  drawbar_pull = rolling*(share*contact.drawbar_pull - (1 - share)*contact_turned.drawbar_pull);
  lateral_force = share*contact.lateral_force + (1 - share)*contact_turned.lateral_force;
  overturning_moment = share*contact.overturning_moment + (1 - share)*contact_turned.overturning_moment;
  turning_moment = rolling*(share*contact.turning_moment - (1 - share)*contact_turned.turning_moment);
  torque = rolling*(share*contact.torque - (1 - share)*contact_turned.torque);
  frame_a.fx = -(drawbar_pull*heading[1] - lateral_force*heading[2]);
  frame_a.fy = -(drawbar_pull*heading[2] + lateral_force*heading[1]);
  frame_a.t = -turning_moment;
  flange_a.tau = torque;
  annotation(
    Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
      Rectangle(extent={{-80,30},{80,-30}}, lineColor={64,64,64}, fillColor={160,160,160}, fillPattern=FillPattern.Solid),
      Line(points={{-60,30},{-60,-30}}), Line(points={{-30,30},{-30,-30}}), Line(points={{0,30},{0,-30}}),
      Line(points={{30,30},{30,-30}}), Line(points={{60,30},{60,-30}}),
      Line(points={{0,-30},{0,-100}}, color={0,0,127}),
      Text(extent={{-150,50},{150,80}}, textString="%name", textColor={0,0,255})}),
    Documentation(info="<html>
<p>The wheel as a tyre of a vehicle seen from above: PlanarMechanics' plane is the ground (x, y on it, phi the yaw), as for PlanarMechanics' <code>SlipBasedWheelJoint</code>, whose connectors it has (<code>frame_a</code>, <code>flange_a</code>, a load input). The contact is the quasi-static one of <code>wheelterrain steady</code> (Components.QuasiStaticWheel: the sinkage at which the soil carries the load, ripple-free, no memory) at the slip, slip angle and turn slip the hub's motion gives:</p>
<ul>
<li>slip from the wheel's spin and the hub's speed along its heading; slip angle atan2(v_lat, |v_long|), + moving toward its left; turn slip the yaw rate over the speed;</li>
<li>back on <code>frame_a</code>: the drawbar pull along the heading and the lateral force across it (Ishigami et al. 2007's side force), in the world frame, and the turning moment M_z about the vertical (the brush model of turn slip and the longitudinal shear across the tread); on <code>flange_a</code> the soil's resisting torque. The overturning moment is an output only (it acts out of this plane).</li>
<li>Rolling backward (omega*R + v &lt; 0: both speeds &lt;= 0 but near rest) is the mirror image of rolling forward, as in the FMU; within the slip's speed floor of the turn of rolling (omega*R + v = 0) the contact is the blend of the two directions (<code>share</code>, Functions.turningWeight; <code>contact_turned</code>, the wheel rolling the other way, its own sinkage solve), as in the FMU's quasi-static mode, so a vehicle stops and reverses on it.</li>
</ul>
<p>Range (asserted with the reason): slip in [-1, 1] (a wheel turning against its hub's motion is outside it), |slip angle| up to ${SLIP_ANGLE_DEG} deg (a wheel moving sideways has no heading), |turn slip| up to ${TURN_SLIP_LIMIT} rad/m (a wheel yawing on the spot is outside the model), a positive load. The soil is the wheel's own (<code>parameters</code>), not a terrain's: in this plane there is no height. For the wheel in the vertical plane of travel (sinkage from the hub's height, the soil's memory), use Wheels.PlanarWheel.</p>
<p>Tested (tests/test_modelica.py, rumoca): a hub moved at a slip angle and a yaw rate gives the steady state's drawbar pull, lateral force and turning moment within 1e-8, turned into the world frame; backward, the mirror image; within the slip's speed floor of the turn of rolling, the FMU's quasi-static blend.</p>
</html>", revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
end HorizontalWheel;
