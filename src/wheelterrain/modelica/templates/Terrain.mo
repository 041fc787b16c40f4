model Terrain "The ground every wheel of a model rolls on: its height, slope and soil at a horizontal position (one inner terrain per model)"
  import SI = Modelica.Units.SI;
  parameter WheelTerrain.Types.Ground ground = WheelTerrain.Types.Ground.flat "the shape"
    annotation(Dialog(group="Shape"));
  parameter SI.Angle slope = 0 "the plane's inclination, rising toward +x (ground = plane)"
    annotation(Dialog(group="Shape", enable=ground == WheelTerrain.Types.Ground.plane));
  parameter Real profile[:, 2] = {{0, 0}, {1, 0}}
    "x [m] and height [m] of the profile's points, x rising (ground = profile): linear between them, level beyond"
    annotation(Dialog(group="Shape", enable=ground == WheelTerrain.Types.Ground.profile));
  parameter Real g[${G}] = cat(1, WheelTerrain.Data.rashidPatch[${SOIL_FIRST}:${SOIL_LAST}], WheelTerrain.Data.terrain[${MAP_AFTER_SOIL}:${G}])
    "the soil and a patch of another, in the terrain map's table order (Functions.soilAt; the Terrain FMU's map): the default preset's soil, no patch"
    annotation(Dialog(group="Soil"));
  replaceable function height = WheelTerrain.Functions.Ground.height(ground=ground, slope=slope, profile=profile)
    constrainedby WheelTerrain.Functions.Interfaces.Height "the height at a horizontal position"
    annotation(Dialog(group="Functions"));
  replaceable function slopeAt = WheelTerrain.Functions.Ground.slope(ground=ground, slope=slope, profile=profile)
    constrainedby WheelTerrain.Functions.Interfaces.Slope "the inclination at a horizontal position, rising toward +x"
    annotation(Dialog(group="Functions"));
  replaceable function soil = WheelTerrain.Functions.soilAt(g=g)
    constrainedby WheelTerrain.Functions.Interfaces.Soil "the soil.* parameters at a horizontal position"
    annotation(Dialog(group="Functions"));
  annotation(defaultComponentName="terrain", defaultComponentPrefixes="inner",
    missingInnerMessage="No \"terrain\" in the model: a WheelTerrain.Terrain (flat, the default preset's soil) is used. Drag WheelTerrain.Terrain into the model to set the ground and its soil.",
    Icon(coordinateSystem(extent={{-100,-100},{100,100}}), graphics={
      Polygon(points={{-100,-100},{-100,-20},{-40,0},{20,-30},{100,10},{100,-100},{-100,-100}}, lineColor={128,96,64}, fillColor={190,150,100}, fillPattern=FillPattern.Solid),
      Text(extent={{-150,60},{150,100}}, textString="%name", textColor={0,0,255})}),
    Documentation(info="<html>
<p>The ground of every <code>Wheels.PlanarWheel</code> in a model, declared once as <code>inner WheelTerrain.Terrain terrain</code> (a wheel finds it as its <code>outer terrain</code>, as MultiBody's parts find <code>world</code>). The plane of travel is PlanarMechanics': x horizontal, y up, gravity along -y.</p>
<ul><li><b>Shape</b> (<code>ground</code>): flat; a plane through the origin rising at <code>slope</code> toward +x; or a profile of heights over x from a table (linear between its points, level beyond them).</li>
<li><b>Soil</b> (<code>g</code>): the terrain map of the Terrain FMU (a soil and a patch [patch.start, patch.end) of another), in x; the soil rows of every wheel's parameters are the terrain's at the wheel's hub.</li>
<li><b>Functions</b>: <code>height(x)</code>, <code>slopeAt(x)</code>, <code>soil(x)</code>, each replaceable (constrained by Functions.Interfaces.Height, Slope, Soil) for a ground of your own.</li></ul>
<p>A wheel takes the terrain under its hub as locally plane (the plane through the height at the hub's x at the slope there): exact on a plane and along a profile's segments; at a profile's point the wheel meets the next segment's plane at once.</p>
</html>", revisions="<html><ul><li>${version}: first version (flat, plane, profile; the terrain map's soil).</li></ul></html>"));
end Terrain;
