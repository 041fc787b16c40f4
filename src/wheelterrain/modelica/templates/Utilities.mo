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
  annotation(Documentation(info="<html><p>Parts the examples use, not meant for a vehicle.</p></html>"));
end Utilities;
