block MapWheel "The Wheel on a terrain map: its soil the Terrain FMU's map gives at the wheel's position"
  extends WheelTerrain.Components.PartialWheel;
  parameter Real g[${G}] = WheelTerrain.Data.terrain
    "the terrain map's parameters in table order (the Terrain FMU's: a soil, a patch of another)";
  input Real position(unit="m") "where the wheel's axle is along the path";
  Boolean on_patch = position >= g[${START}] and position < g[${END}]
    "the wheel on the map's patch [patch.start, patch.end): its edges are events";
equation
  pk = cat(1, p[1:${SOIL_FIRST}], if on_patch then g[${PATCH_FIRST}:${PATCH_LAST}] else g[${MAP_SOIL_FIRST}:${MAP_SOIL_LAST}], p[${SOIL_AFTER}:${N}]);
  annotation(Documentation(info="<html><p>The soil rows of the contact's parameters (soil.*) are the terrain map's at the wheel's position, the patch's where it lies (the rule of Functions.soilAt, the Terrain FMU's map, written as an equation so that the tool meets the patch's edges as events: the soil changes there at once); the rest are p's. As the FMUs' model exchange, no rut is recorded along the track.</p></html>"));
end MapWheel;
