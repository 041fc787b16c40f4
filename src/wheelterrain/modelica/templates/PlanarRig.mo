model PlanarRig "The paper's single-wheel rig with a PlanarWheel: a carriage moves the hub at the set slip and presses it down with the load, an MSL speed loop (Utilities.SpeedDrive) drives the axle"
  import SI = Modelica.Units.SI;
  parameter Real slip_paper = 0 "the paper's slip s the carriage is set to";
  parameter SI.Angle angle = 0 "the terrain's and the carriage's guide's inclination (0: the paper's level rig)";
  parameter SI.Force load = ${rig_load} "rig.load: presses the hub toward the terrain, along its normal";
  parameter SI.Mass mass = ${rig_mass} "rig.mass: moves with the wheel across the guide";
  parameter SI.MomentOfInertia wheel_inertia = ${rig_wheel_inertia} "rig.wheel_inertia";
  parameter SI.AngularVelocity speed_bandwidth = ${rig_speed_bandwidth} "rig.speed_bandwidth: both poles of the speed loop";
  parameter SI.Velocity rim_speed = ${rig_rim_speed} "rig.rim_speed";
  parameter SI.Length sinkage_start = ${sinkage_start} "where the wheel starts (the reference results start there)";
  inner WheelTerrain.Terrain terrain(ground=WheelTerrain.Types.Ground.plane, slope=angle)
    annotation(Placement(transformation(extent={{-100,-100},{-60,-60}})));
  WheelTerrain.Wheels.PlanarWheel wheel "the default preset"
    annotation(Placement(transformation(extent={{0,-40},{40,0}})));
  WheelTerrain.Examples.Utilities.RigCarriage carriage(angle=angle, speed=rim_speed/(1 + slip_paper), mass=mass, load=load,
    height_start=wheel.contact_radius - sinkage_start)
    annotation(Placement(transformation(extent={{-60,-40},{-20,0}})));
  final parameter SI.Length slip_radius = wheel.parameters.wheel.radius + wheel.parameters.options.slip_radius_factor*wheel.parameters.grouser.height "R_ref";
  final parameter SI.AngularVelocity omega_ref = rim_speed/slip_radius;
  WheelTerrain.Examples.Utilities.SpeedDrive drive(J=wheel_inertia, bandwidth=speed_bandwidth, w_ref=omega_ref, tau_max=Modelica.Constants.inf)
    "the rig's motor and speed loop (the rig's motor has no torque limit)"
    annotation(Placement(transformation(extent={{80,-30},{60,-10}})));
  SI.Force drawbar_pull = wheel.drawbar_pull;
  SI.Length sinkage = wheel.sinkage;
  SI.Force normal_force = wheel.normal_force;
  SI.Velocity sinkage_rate = wheel.sinkage_rate;
  SI.AngularVelocity wheel_speed = wheel.wheel_speed;
  SI.Angle wheel_angle = drive.inertia.phi;
  SI.Length plastic_sinkage = wheel.plastic_sinkage;
  SI.Torque torque = wheel.torque;
equation
  connect(carriage.frame_b, wheel.frame_a) annotation(Line(points={{-20,-20},{0,-20}}));
  connect(drive.flange_b, wheel.flange_a) annotation(Line(points={{60,-20},{40,-20}}));
  connect(drive.support, wheel.support) annotation(Line(points={{60,-26},{50,-26},{50,-46},{20,-46},{20,-40}}));
  annotation(${experiment},
    Diagram(coordinateSystem(extent={{-100,-100},{100,100}})),
    Documentation(info="<html><p>Examples.Rig with the wheel a Wheels.PlanarWheel on an inner Terrain: the carriage (Examples.Utilities.RigCarriage, PlanarMechanics' Frame connector) moves the hub along its guide at the set slip, lets it move across the guide with the rig's mass and presses it toward the terrain with the load; the speed loop (Examples.Utilities.SpeedDrive, the rover's drive without a torque limit, its housing on the wheel's support) drives the axle through the wheel's inertia. With <code>angle</code> = 0 it is the paper's rig: its reference is RigC1's (Resources/Reference/WheelTerrain/Examples/PlanarRig/PlanarRig.csv, the Python model's rig at slip_paper 0); at 0.25, 0.5, 0.75 RigC2 ... RigC4's. Tilted (<code>angle</code> &lt;&gt; 0), the terrain and the guide incline together and the load stays along the terrain's normal: the same trajectory in the terrain's frame.</p></html>",
      revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
end PlanarRig;
