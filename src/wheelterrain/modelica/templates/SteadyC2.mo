model SteadyC2 "The quasi-static wheel at the paper's C2: 62 N, the paper's slip 0.25, the default preset"
  parameter Real slip_paper = 0.25 "the paper's slip s";
  WheelTerrain.Components.QuasiStaticWheel wheel(load=${steady_load},
    slip=WheelTerrain.Functions.slipFromPaper(slip_paper), slip_angle=0, turn_slip=0);
  Real sinkage(unit="m") = wheel.sinkage;
  Real drawbar_pull(unit="N") = wheel.drawbar_pull;
  Real slip(unit="1") = wheel.slip "the model's slip";
  Real torque(unit="N.m") = wheel.torque;
  annotation(${experiment},
    Documentation(info="<html><p>Reference: Resources/Reference/WheelTerrain/Examples/SteadyC2/SteadyC2.csv (the Python model's steady state).</p></html>"));
end SteadyC2;
