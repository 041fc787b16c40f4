model SlipRamp "The quasi-static wheel at ${steady_load} N as its slip ramps from ${ramp_start} by ${ramp_rate} per second"
  WheelTerrain.Components.QuasiStaticWheel wheel(load=${steady_load}, slip=${ramp_start} + ${ramp_rate}*time,
    slip_angle=0, turn_slip=0);
  Real sinkage(unit="m") = wheel.sinkage;
  Real drawbar_pull(unit="N") = wheel.drawbar_pull;
  Real slip(unit="1") = wheel.slip "the model's slip";
  Real torque(unit="N.m") = wheel.torque;
  annotation(${experiment},
    Documentation(info="<html><p>Reference: Resources/Reference/WheelTerrain/Examples/SlipRamp/SlipRamp.csv (the Python model's steady state at each output time).</p></html>"));
end SlipRamp;
