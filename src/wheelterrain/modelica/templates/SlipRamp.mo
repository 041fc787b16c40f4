model SlipRamp "The quasi-static wheel at ${steady_load} N as its slip ramps from ${ramp_start} by ${ramp_rate} per second"
  WheelTerrain.Components.QuasiStaticWheel wheel
    annotation(Placement(transformation(extent={{-20,-20},{20,20}})));
  Modelica.Blocks.Sources.Constant load(k=${steady_load}) "the wheel's load [N]"
    annotation(Placement(transformation(extent={{-80,50},{-60,70}})));
  Modelica.Blocks.Sources.RealExpression slipRamp(y=${ramp_start} + ${ramp_rate}*time)
    "the model's slip, ramping (an expression: no events, unlike a Ramp's start and end)"
    annotation(Placement(transformation(extent={{-80,10},{-60,30}})));
  Modelica.Blocks.Sources.Constant straight(k=0) "driven straight: no slip angle, no turn slip"
    annotation(Placement(transformation(extent={{-80,-40},{-60,-20}})));
  Real sinkage(unit="m") = wheel.sinkage;
  Real drawbar_pull(unit="N") = wheel.drawbar_pull;
  Real slip(unit="1") = wheel.slip "the model's slip";
  Real torque(unit="N.m") = wheel.torque;
equation
  connect(load.y, wheel.load) annotation(Line(points={{-59,60},{-40,60},{-40,12},{-24,12}}, color={0,0,127}));
  connect(slipRamp.y, wheel.slip) annotation(Line(points={{-59,20},{-42,20},{-42,4},{-24,4}}, color={0,0,127}));
  connect(straight.y, wheel.slip_angle) annotation(Line(points={{-59,-30},{-44,-30},{-44,-4},{-24,-4}}, color={0,0,127}));
  connect(straight.y, wheel.turn_slip) annotation(Line(points={{-59,-30},{-44,-30},{-44,-12},{-24,-12}}, color={0,0,127}));
  annotation(${experiment},
    Documentation(info="<html><p>Reference: Resources/Reference/WheelTerrain/Examples/SlipRamp/SlipRamp.csv (the Python model's steady state at each output time).</p></html>"));
end SlipRamp;
