model PlanarWheel "A rigid wheel with grousers on the terrain's soil in the vertical plane of travel: its hub a PlanarMechanics frame, its axle a Rotational flange"
  import SI = Modelica.Units.SI;
  outer WheelTerrain.Terrain terrain "the ground (one inner WheelTerrain.Terrain in the model)";
  replaceable parameter WheelTerrain.Records.Presets.RashidPatch parameters
    constrainedby WheelTerrain.Records.Parameters
    "the wheel and the contact model (a preset; the soil rows are the terrain's)"
    annotation(choicesAllMatching=true);
  replaceable function contactFunction = WheelTerrain.Functions.contact
    constrainedby WheelTerrain.Functions.Interfaces.Contact
    "the contact: Functions.contact (generated, the default) or Functions.External.contact (CasADi's C)"
    annotation(Dialog(tab="Advanced"));
  PlanarMechanics.Interfaces.Frame_a frame_a
    "the hub: x forward, y up (PlanarMechanics' plane of travel), phi its pitch, counter-clockwise"
    annotation(Placement(transformation(extent={{-116,-16},{-84,16}})));
  Modelica.Mechanics.Rotational.Interfaces.Flange_a flange_a
    "the axle: the wheel's angle (absolute, as every Rotational flange's), positive rolling toward +x"
    annotation(Placement(transformation(extent={{90,-10},{110,10}})));
  Modelica.Mechanics.Rotational.Interfaces.Support support
    "the hub's side of the axle: its angle the hub's (in the wheel's sense), its torque onto the hub: mount the drive's support here"
    annotation(Placement(transformation(extent={{90,-70},{110,-50}})));
  final parameter Real p[${N}] = WheelTerrain.Records.parameterVector(parameters)
    "the parameters in table order";
  final parameter SI.Length contact_radius = parameters.wheel.radius + parameters.options.contact_radius_factor*parameters.grouser.height
    "R_c: the circle the sinkage is measured to";
  SI.Angle surface_slope "the terrain's inclination under the hub, rising toward +x";
  SI.Length clearance "the hub's height above the terrain, along the terrain's normal";
  SI.Length sinkage "of the contact circle below the terrain's surface";
  SI.Velocity sinkage_rate "d(sinkage)/dt";
  SI.Velocity carriage_speed "the hub's speed along the terrain, forward";
  SI.AngularVelocity wheel_speed "the wheel's rolling rate: the axle's turning less the hub's pitch rate";
  Real slip(unit="1") = contact.slip "the model's slip: traction driving, skid braking (-1 locked)";
  SI.Force normal_force = contact.normal_force "the soil's force on the wheel along the terrain's normal";
  SI.Force drawbar_pull = contact.drawbar_pull "the soil's force on the wheel along the terrain, forward";
  SI.Torque torque = contact.torque "the torque the soil resists the wheel's rolling with (the axle carries it)";
  SI.Length plastic_sinkage = contact.plastic_sinkage "the deepest the wheel has pressed the soil under it";
  WheelTerrain.Components.SoilWheel contact(p=p, redeclare function contactFunction = contactFunction,
    soil=terrain.soil(frame_a.x), sinkage=sinkage, sinkage_rate=sinkage_rate, wheel_speed=wheel_speed,
    carriage_speed=carriage_speed, slip_angle=0, yaw_rate=0)
    "the contact with the soil's memory (the WheelTerrain FMU's), the terrain's soil at the hub"
    annotation(Placement(transformation(extent={{-20,-60},{20,-20}})));
equation
  surface_slope = terrain.slopeAt(frame_a.x);
  clearance = (frame_a.y - terrain.height(frame_a.x))*cos(surface_slope);
  sinkage = contact_radius - clearance;
  carriage_speed = der(frame_a.x)*cos(surface_slope) + der(frame_a.y)*sin(surface_slope);
  sinkage_rate = der(frame_a.x)*sin(surface_slope) - der(frame_a.y)*cos(surface_slope);
  wheel_speed = der(flange_a.phi);
  // the hub's rotation in the wheel's sense (rolling toward +x is clockwise in the x-y view)
  support.phi = -frame_a.phi;
  // the wheel is massless and its bearing passes no torque: the hub carries the soil's force,
  // the axle the soil's torque, and the torque on the support (a drive's housing) reaches the
  // hub (MultiBody.Parts.Mounting1D's rule for a 1-D support on a body)
  frame_a.fx = -(drawbar_pull*cos(surface_slope) - normal_force*sin(surface_slope));
  frame_a.fy = -(drawbar_pull*sin(surface_slope) + normal_force*cos(surface_slope));
  frame_a.t = support.tau;
  flange_a.tau = torque;
  annotation(
    Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
      Rectangle(extent={{-100,-100},{100,-62}}, lineColor={128,96,64}, fillColor={190,150,100}, fillPattern=FillPattern.Solid),
      Ellipse(extent={{-70,80},{70,-60}}, lineColor={64,64,64}, fillColor={160,160,160}, fillPattern=FillPattern.Solid),
      Ellipse(extent={{-50,60},{50,-40}}, lineColor={64,64,64}, fillColor={220,220,220}, fillPattern=FillPattern.Solid),
      Line(points={{0,80},{0,92}}, thickness=1), Line(points={{0,-60},{0,-72}}, thickness=1),
      Line(points={{-70,10},{-82,10}}, thickness=1), Line(points={{70,10},{82,10}}, thickness=1),
      Line(points={{-84,0},{0,10}}, color={95,95,95}), Line(points={{0,10},{90,0}}, color={64,64,64}),
      Text(extent={{-150,100},{150,130}}, textString="%name", textColor={0,0,255})}),
    Documentation(info="<html>
<p>The wheel of the WheelTerrain FMU (Components.SoilWheel: the contact with the soil's memory, the grouser ripple, the model's slip) as a component in the vertical plane of travel: PlanarMechanics' plane, x horizontal and forward, y up, gravity along -y. Connect <code>frame_a</code> to the body carrying the axle and <code>flange_a</code> to its drive; put one <code>inner WheelTerrain.Terrain terrain</code> in the model.</p>
<ul>
<li><b>Load from the hub's motion</b>: the sinkage is the contact circle's depth below the terrain's plane under the hub, R_c minus the hub's clearance along the terrain's normal; its rate and the axle's speed along the terrain come from the hub's velocity. The normal load is not an input: it is what the soil carries at that sinkage.</li>
<li><b>Forces back on the hub</b>: the drawbar pull (along the terrain) and the normal force (along its normal) in PlanarMechanics' world frame on <code>frame_a</code>; the soil's torque on <code>flange_a</code>. The wheel is massless (give its mass to the body and its spin inertia to a Rotational.Components.Inertia on the axle).</li>
<li><b>The axle and the drive's mounting</b>: <code>flange_a.phi</code> is the wheel's angle, absolute as every Rotational flange's and as PlanarMechanics' wheel joints take it (SlipBasedWheelJoint rolls at der(flange_a.phi)), positive rolling forward (toward +x, clockwise in the x-y view): an Inertia on it carries the wheel's spin inertia with the hub's pitch counted, and a SpeedSensor on it reads the wheel's rolling rate. <code>support</code> is the hub's side of the axle (its angle the hub's, in the wheel's sense): connect the drive's support there (a motor in the hub; Rotational.Sources.Torque with <code>useSupport=true</code>), and its reaction acts on <code>frame_a</code>, as MultiBody.Parts.Mounting1D mounts a 1-D support on a body. A relative encoder is a Rotational.Sensors.RelSpeedSensor between <code>support</code> and <code>flange_a</code>. Left unconnected, the support takes no torque: the drive's reaction goes to the ground, not to the hub (the rule of a grounded 1-D support).</li>
<li><b>Soil</b>: the terrain's (<code>terrain.soil</code> at the hub's x) in place of the soil rows of <code>parameters</code>; the soil's memory (the plastic sinkage) is the wheel's state, fresh soil at the start. No rut is recorded along the track (the FMUs' model exchange).</li>
<li><b>Range</b>: forward, braking to the locked wheel, at rest, through standstill and backward (omega*R + v &lt; 0: the mirror image of rolling forward). The slip is regularised through standstill (its denominator floored at ${SLIP_SPEED_FLOOR} m/s, as PlanarMechanics' SlipBasedWheelJoint floors its adhesion velocity), and within that speed of the turn of rolling the contact is the blend of the two directions (the FMU's), so a vehicle stops and reverses on the wheel (Examples.PlanarRover with <code>rim_speed_end</code> negative). A wheel turning against its hub's motion beyond that floor (spinning forward while the hub slides backward, or the reverse) is outside the contact's slip range and stops the simulation at the slip's assert, as the FMU refuses it. Lateral forces do not act in this plane (slip angle and yaw rate 0).</li>
</ul>
<p>Tested (tests/test_modelica.py, rumoca with MSL 4.1.0 and PlanarMechanics 1.6.0): Examples.PlanarRig reproduces the paper's rig on Components.Contact (Resources/Reference/Rig*.csv) at the four slips; the same rig tilted onto a plane of 15 deg, its load along the plane's normal, gives the level rig's trajectory. rumoca 0.10 cannot run PlanarMechanics' Body and PlanarWorld (an outer reference of the body is not resolved), so the tests carry the hub on a body written with PlanarMechanics' Frame connector (Examples.Utilities.RigCarriage).</p>
</html>", revisions="<html><ul><li>${version}: the axle flange's angle absolute and the drive mounted on <code>support</code> (before: the angle relative to the hub and the axle's torque on the hub, PlanarMechanics.Joints.Revolute's convention, which grounds the drive line's inertia and loses its reaction on the hub); first version.</li></ul></html>"));
end PlanarWheel;
