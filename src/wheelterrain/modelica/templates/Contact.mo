model Contact "The wheel-soil contact between a wheel's hub, its axle and the ground, with the soil's memory"
  import SI = Modelica.Units.SI;
  replaceable parameter WheelTerrain.Records.Presets.RashidPatch parameters
    constrainedby WheelTerrain.Records.Parameters
    "the soil, wheel and model parameters: a preset (redeclare) with any value changed";
  final parameter Real p[${N}] = WheelTerrain.Records.parameterVector(parameters)
    "the parameters in table order";
  parameter SI.Length plastic_sinkage_start = 0 "the soil's memory at the start";
  replaceable function contactFunction = WheelTerrain.Functions.contact
    constrainedby WheelTerrain.Functions.Interfaces.Contact
    "the contact: Functions.contact (generated, the default) or Functions.External.contact (CasADi's C)";
  Modelica.Mechanics.Rotational.Interfaces.Flange_a hub "the wheel's hub: its angle turns the wheel forward"
    annotation(Placement(transformation(extent={{-110,-10},{-90,10}})));
  Modelica.Mechanics.Translational.Interfaces.Flange_a axle "the axle, horizontally: s forward"
    annotation(Placement(transformation(extent={{-10,90},{10,110}})));
  Modelica.Mechanics.Translational.Interfaces.Flange_a vertical "the axle, vertically: s up, s = -sinkage"
    annotation(Placement(transformation(extent={{-10,-110},{10,-90}})));
  SI.Length sinkage "below the undisturbed surface";
  SI.Velocity sinkage_rate;
  SI.AngularVelocity wheel_speed;
  SI.Velocity carriage_speed;
  Real slip(unit="1") "the model's slip: traction driving, skid braking (-1 locked)";
  SI.Length plastic_sinkage(start=plastic_sinkage_start, fixed=true) "the deepest the wheel has pressed the soil under it";
  SI.Force normal_force "the soil's force on the wheel, up";
  SI.Force drawbar_pull "the soil's net force on the wheel, forward";
  SI.Torque torque "the torque the soil resists the wheel's turning with";
  SI.Length rut_left "the rut the wheel leaves";
  SI.Pressure rut_pressure_left "the pressure the wheel pressed that rut to (its soil.rut_pressure for the next wheel)";
  Real y[${CONTACT_ROWS}] "every output of Functions.contact";
equation
  sinkage = -vertical.s;
  sinkage_rate = der(sinkage);
  wheel_speed = der(hub.phi);
  carriage_speed = der(axle.s);
  slip = WheelTerrain.Functions.slipFromSpeeds(wheel_speed, carriage_speed, p);
  assert(slip >= -1 and slip <= 1, "Contact: the slip left the model's range [-1, 1] (a wheel or axle moving backward)");
  y = contactFunction(sinkage, sinkage_rate, slip, hub.phi, plastic_sinkage, carriage_speed, p);
  der(plastic_sinkage) = y[WheelTerrain.Functions.Index.plastic_rate];
  normal_force = y[WheelTerrain.Functions.Index.normal_force];
  drawbar_pull = y[WheelTerrain.Functions.Index.drawbar_pull];
  torque = y[WheelTerrain.Functions.Index.torque];
  rut_left = y[WheelTerrain.Functions.Index.rut_left];
  rut_pressure_left = y[WheelTerrain.Functions.Index.rut_pressure_left];
  vertical.f = -normal_force;
  axle.f = -drawbar_pull;
  hub.tau = torque;
  annotation(Documentation(info="<html><p>The contact of the WheelTerrain FMU on MSL flanges. Signs as MSL's: a flange's force or torque is what acts on this component, so the soil's force on the wheel is minus it.</p></html>"));
end Contact;
