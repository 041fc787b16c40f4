package Utilities "Parts the examples use"
  model RigCarriage "The single-wheel rig's carriage on PlanarMechanics' Frame: it moves the hub along a guide at a set speed, lets it move freely across the guide with a mass, presses it down with a load and holds its pitch"
    import SI = Modelica.Units.SI;
    parameter SI.Angle angle = 0 "the guide's inclination, rising toward +x";
    parameter SI.Velocity speed "along the guide";
    parameter SI.Mass mass "moves with the hub across the guide";
    parameter SI.Force load "presses the hub across the guide, toward the ground";
    parameter SI.Length height_start "the hub's distance from the guide's line through the origin, across it, at the start";
    PlanarMechanics.Interfaces.Frame_b frame_b "the hub"
      annotation(Placement(transformation(extent={{84,-16},{116,16}})));
    SI.Position s(start=0, fixed=true) "along the guide";
    SI.Position h(start=height_start, fixed=true) "across the guide";
    SI.Velocity v(start=0, fixed=true) "d(h)/dt";
  equation
    der(s) = speed;
    der(h) = v;
    mass*der(v) = -frame_b.fx*sin(angle) + frame_b.fy*cos(angle) - load;
    frame_b.x = s*cos(angle) - h*sin(angle);
    frame_b.y = s*sin(angle) + h*cos(angle);
    frame_b.phi = angle;
    annotation(Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
        Rectangle(extent={{-100,40},{80,-40}}, lineColor={0,0,0}, fillColor={200,200,200}, fillPattern=FillPattern.Solid),
        Line(points={{-100,-60},{100,-60}}, thickness=0.5),
        Text(extent={{-150,60},{150,100}}, textString="%name", textColor={0,0,255})}),
      Documentation(info="<html><p>A body written with PlanarMechanics' Frame connector: rumoca 0.10 cannot run PlanarMechanics.Parts.Body (its outer PlanarWorld is not resolved), so the rig examples carry the hub on this. In a tool that runs PlanarMechanics, a Parts.Body on Joints.Prismatic guides does the same.</p></html>",
        revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
  end RigCarriage;
  model PlanarBody "A rigid body in the plane on PlanarMechanics' Frame, its frame at its centre of mass, gravity turned by an input: PlanarMechanics.Parts.Body for rumoca"
    import SI = Modelica.Units.SI;
    parameter SI.Mass m "the body's mass";
    parameter SI.MomentOfInertia I "about its centre of mass, normal to the plane";
    parameter SI.Acceleration g "gravity";
    parameter SI.Position x_start = 0 "of the centre of mass";
    parameter SI.Position y_start = 0 "of the centre of mass";
    parameter SI.Angle phi_start = 0 "the body's angle, counter-clockwise";
    parameter SI.Velocity vx_start = 0;
    parameter SI.Velocity vy_start = 0;
    parameter SI.AngularVelocity w_start = 0;
    Modelica.Blocks.Interfaces.RealInput tilt(unit="rad")
      "the ground's inclination under the body, rising toward +x: gravity is turned by it, g*{-sin(tilt), -cos(tilt)} (0: straight down)"
      annotation(Placement(transformation(extent={{-140,-20},{-100,20}})));
    PlanarMechanics.Interfaces.Frame_a frame_a "at the centre of mass"
      annotation(Placement(transformation(extent={{84,-16},{116,16}})));
    SI.Position x(start=x_start, fixed=true);
    SI.Position y(start=y_start, fixed=true);
    SI.Angle phi(start=phi_start, fixed=true);
    SI.Velocity vx(start=vx_start, fixed=true);
    SI.Velocity vy(start=vy_start, fixed=true);
    SI.AngularVelocity w(start=w_start, fixed=true);
  equation
    frame_a.x = x;
    frame_a.y = y;
    frame_a.phi = phi;
    der(x) = vx;
    der(y) = vy;
    der(phi) = w;
    m*der(vx) = frame_a.fx - m*g*sin(tilt);
    m*der(vy) = frame_a.fy - m*g*cos(tilt);
    I*der(w) = frame_a.t;
    annotation(Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
        Rectangle(extent={{-100,40},{100,-40}}, lineColor={0,0,0}, fillColor={0,127,255}, fillPattern=FillPattern.Solid, radius=10),
        Text(extent={{-150,60},{150,100}}, textString="%name", textColor={0,0,255})}),
      Documentation(info="<html><p>The equations of PlanarMechanics.Parts.Body (mass, inertia, gravity at the centre of mass, its frame there) written with PlanarMechanics' Frame connector: rumoca 0.10 cannot run Parts.Body (its outer PlanarWorld is not resolved), so the rover from standard parts carries its chassis on this. Gravity is turned by <code>tilt</code>: the body in the frame of a ground inclined by <code>tilt</code> (x along it, y along its normal), the Python rover's slope input, so that a slope that changes in time is the same run in both. In a tool that runs PlanarMechanics, a Parts.Body on a PlanarWorld whose gravity is the tilted one does the same for a constant tilt.</p></html>",
        revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
  end PlanarBody;
  model SpeedDrive "A wheel's drive from MSL parts: a PI speed loop on the axle's spin (a constant command or a ramp to another), the torque limited, the motor's housing on the wheel's support"
    import SI = Modelica.Units.SI;
    parameter SI.MomentOfInertia J "the spin inertia about the axle (wheel and motor)";
    parameter SI.AngularVelocity bandwidth "both poles of the speed loop at -bandwidth";
    parameter SI.AngularVelocity w_ref "the commanded spin";
    parameter SI.Torque tau_max "the motor's torque limit";
    parameter SI.AngularVelocity w_end = w_ref "the spin the command ramps to (w_ref: no change)";
    parameter SI.Time ramp_start_time = 0 "when the command starts to ramp from w_ref to w_end";
    parameter SI.Time ramp_duration(min=Modelica.Constants.small) = 1 "how long the ramp takes";
    Modelica.Mechanics.Rotational.Interfaces.Flange_b flange_b "to the wheel's axle (PlanarWheel.flange_a)"
      annotation(Placement(transformation(extent={{90,-10},{110,10}})));
    Modelica.Mechanics.Rotational.Interfaces.Support support "to the hub (PlanarWheel.support): the motor's housing"
      annotation(Placement(transformation(extent={{90,-70},{110,-50}})));
    Modelica.Blocks.Sources.RealExpression reference(y=w_ref + (w_end - w_ref)*noEvent(min(max((time - ramp_start_time)/ramp_duration, 0), 1)))
      "w_ref, ramping to w_end from ramp_start_time (exactly w_ref with w_end = w_ref; no events, as a Ramp's, in the examples' output grid)"
      annotation(Placement(transformation(extent={{-100,40},{-80,60}})));
    Modelica.Blocks.Math.Feedback error
      annotation(Placement(transformation(extent={{-70,40},{-50,60}})));
    Modelica.Blocks.Continuous.PI controller(k=2*bandwidth*J, T=2/bandwidth, initType=Modelica.Blocks.Types.Init.InitialState, x_start=0)
      annotation(Placement(transformation(extent={{-40,40},{-20,60}})));
    Modelica.Blocks.Nonlinear.Limiter limiter(uMax=tau_max)
      annotation(Placement(transformation(extent={{-10,40},{10,60}})));
    Modelica.Mechanics.Rotational.Sources.Torque motor(useSupport=true)
      annotation(Placement(transformation(extent={{20,-10},{40,10}})));
    Modelica.Mechanics.Rotational.Components.Inertia inertia(J=J, phi(start=0, fixed=true), w(start=w_ref, fixed=true))
      annotation(Placement(transformation(extent={{50,-10},{70,10}})));
    Modelica.Mechanics.Rotational.Sensors.SpeedSensor speed
      annotation(Placement(transformation(extent={{50,-50},{30,-30}})));
  equation
    connect(reference.y, error.u1) annotation(Line(points={{-79,50},{-68,50}}, color={0,0,127}));
    connect(speed.w, error.u2) annotation(Line(points={{29,-40},{-60,-40},{-60,42}}, color={0,0,127}));
    connect(error.y, controller.u) annotation(Line(points={{-51,50},{-42,50}}, color={0,0,127}));
    connect(controller.y, limiter.u) annotation(Line(points={{-19,50},{-12,50}}, color={0,0,127}));
    connect(limiter.y, motor.tau) annotation(Line(points={{11,50},{14,50},{14,0},{18,0}}, color={0,0,127}));
    connect(motor.flange, inertia.flange_a) annotation(Line(points={{40,0},{50,0}}));
    connect(inertia.flange_b, flange_b) annotation(Line(points={{70,0},{100,0}}));
    connect(speed.flange, inertia.flange_b) annotation(Line(points={{50,-40},{80,-40},{80,0},{70,0}}));
    connect(motor.support, support) annotation(Line(points={{30,-10},{30,-60},{100,-60}}));
    annotation(Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
        Rectangle(extent={{-80,50},{60,-50}}, lineColor={64,64,64}, fillColor={160,160,160}, fillPattern=FillPattern.Solid),
        Rectangle(extent={{60,10},{100,-10}}, lineColor={64,64,64}, fillColor={200,200,200}, fillPattern=FillPattern.Solid),
        Text(extent={{-80,20},{60,-20}}, textString="PI", textColor={0,0,0}),
        Text(extent={{-150,60},{150,100}}, textString="%name", textColor={0,0,255})}),
      Documentation(info="<html><p>The Python rover's speed loop from MSL parts: the spin's error to the command (<code>w_ref</code>, or from <code>ramp_start_time</code> a ramp over <code>ramp_duration</code> to <code>w_end</code>: through zero, the vehicle stops and reverses) into a PI with both closed-loop poles at -<code>bandwidth</code> (k = 2*bandwidth*J, T = 2/bandwidth), limited to +-<code>tau_max</code>, a torque source whose housing is the wheel's support (the hub), the spin inertia J on the axle, the spin read by a SpeedSensor on it (the wheel's rolling rate, as the Python rover's loop reads it; a motor's encoder would read it relative to the hub). The limiter has no anti-windup (the Python rover's loop stops integrating while saturated): the same while the loop is not saturated.</p></html>",
        revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
  end SpeedDrive;
  annotation(Documentation(info="<html><p>Parts the examples use, not meant for a vehicle.</p></html>"));
end Utilities;
