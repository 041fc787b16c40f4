model PlanarRover "The rover from standard parts: a body, two axles (PlanarMechanics' FixedTranslation), four PlanarWheels, four speed-loop drives from MSL parts, one inner Terrain"
  import SI = Modelica.Units.SI;
  parameter Real r[${R}] = WheelTerrain.Data.rover
    "the rover's parameters (the rover.* rows, Data.rover's order; its input profile: the rover.ramp_time ... rows)";
  parameter SI.Length heave_start = ${heave_start} "the axle line's depth in the soil at the start";
  final parameter SI.Mass mass = r[${mass}] "rover.mass";
  final parameter SI.MomentOfInertia pitch_inertia = r[${pitch_inertia}] "rover.pitch_inertia";
  final parameter SI.Length wheelbase = r[${wheelbase}] "rover.wheelbase";
  final parameter SI.Length cg_forward = r[${cg_forward}] "rover.cg_forward";
  final parameter SI.Length cg_height = r[${cg_height}] "rover.cg_height";
  final parameter SI.Acceleration gravity = r[${gravity}] "rover.gravity";
  final parameter SI.Velocity rim_speed = r[${rim_speed}] "rover.rim_speed";
  final parameter SI.Length slip_radius = r[${slip_radius}] "rover.slip_radius";
  final parameter SI.Time ramp_time = r[${ramp_time}] "rover.ramp_time";
  final parameter SI.AngularVelocity slope_rate = r[${slope_rate}] "rover.slope_rate";
  final parameter SI.AngularVelocity slope_rate_after = r[${slope_rate_after}] "rover.slope_rate_after";
  final parameter SI.Angle slope_bound = r[${slope_bound}] "rover.slope_bound";
  parameter SI.Velocity rim_speed_end = rim_speed "the rim speed the drives' commands ramp to (rim_speed: no change; negative: the rover stops and reverses)";
  parameter SI.Time change_start_time = 0 "when the commands start to ramp to rim_speed_end";
  parameter SI.Time change_duration = 1 "how long the ramp takes";
  final parameter SI.Length contact_radius = front_left.contact_radius "R_c of every wheel";
  inner PlanarMechanics.PlanarWorld planarWorld(enableAnimation=false)
    "PlanarMechanics' world (the axles' parts refer to it)"
    annotation(Placement(transformation(extent={{-100,60},{-80,80}})));
  inner WheelTerrain.Terrain terrain "flat, the default preset's soil"
    annotation(Placement(transformation(extent={{-100,-100},{-80,-80}})));
  Modelica.Blocks.Sources.RealExpression slope(y=min(max(slope_rate*min(time, ramp_time) + slope_rate_after*max(time - ramp_time, 0), -slope_bound), slope_bound))
    "the ground's inclination in time (the Python rover's input profile)"
    annotation(Placement(transformation(extent={{-100,20},{-80,40}})));
  WheelTerrain.Examples.Utilities.PlanarBody body(m=mass, I=pitch_inertia, g=gravity, x_start=0,
    y_start=contact_radius - heave_start + cg_height, vx_start=rim_speed)
    "the chassis, its frame at the centre of mass"
    annotation(Placement(transformation(extent={{-60,20},{-20,40}})));
  PlanarMechanics.Parts.FixedTranslation front(r={wheelbase/2 - cg_forward, -cg_height}, animate=false)
    "from the centre of mass to the front axle"
    annotation(Placement(transformation(extent={{0,40},{20,60}})));
  PlanarMechanics.Parts.FixedTranslation rear(r={-wheelbase/2 - cg_forward, -cg_height}, animate=false)
    "from the centre of mass to the rear axle"
    annotation(Placement(transformation(extent={{0,-30},{20,-10}})));
${wheels}
  SI.Position position = body.x + cg_height*sin(body.phi)
    "of the reference point (the axle line below the centre of mass), along the ground";
  SI.Velocity speed = body.vx + cg_height*cos(body.phi)*body.w "d(position)/dt";
  SI.Length heave = contact_radius - (body.y - cg_height*cos(body.phi))
    "the reference point's sinkage: the contact circle's depth there";
  SI.Angle pitch = -body.phi "nose down positive";
equation
  connect(slope.y, body.tilt) annotation(Line(points={{-79,30},{-64,30}}, color={0,0,127}));
  connect(body.frame_a, front.frame_a) annotation(Line(points={{-20,30},{-10,30},{-10,50},{0,50}}));
  connect(body.frame_a, rear.frame_a) annotation(Line(points={{-20,30},{-10,30},{-10,-20},{0,-20}}));
${connections}
  annotation(${experiment},
    Diagram(coordinateSystem(extent={{-100,-100},{100,100}})),
    Documentation(info="<html><p>Examples.FMUTwin.Rover's rover built the way a Modelica user builds a vehicle: a body (Utilities.PlanarBody, PlanarMechanics.Parts.Body's equations), its axles PlanarMechanics.Parts.FixedTranslation from the centre of mass (<code>rover.wheelbase</code>, <code>rover.cg_forward</code>, <code>rover.cg_height</code>), two Wheels.PlanarWheel on each axle (the left and the right wheel of an axle run alike in the plane; each its own grouser phase, <code>rover.grouser_phase.*</code>), each driven by a Utilities.SpeedDrive (MSL's PI, Limiter, Torque, Inertia and SpeedSensor; the motor's housing on the wheel's <code>support</code>, so its reaction pitches the body), one inner Terrain. No RoverChassis, no signal block between the parts: the connections are the rover.</p>
<p>It is the Python model's rover (the RoverChassis FMU's equations): the same trajectory as Examples.FMUTwin.Rover, whose reference it reproduces (${reference}). The ground is flat and the slope profile (<code>rover.ramp_time</code> ... rows) turns gravity in the ground's frame, as the Python rover's slope input does: PlanarRoverSlope is RoverSlope's climb. Tested in rumoca with MSL 4.1.0 and PlanarMechanics 1.6.0 (tests/test_modelica.py); the body is Utilities.PlanarBody because rumoca 0.10 cannot run PlanarMechanics.Parts.Body.</p></html>",
      revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
end PlanarRover;
