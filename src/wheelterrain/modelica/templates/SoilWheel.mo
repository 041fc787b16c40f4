block SoilWheel "The Wheel with the soil rows of its parameters as an input: a terrain's soil under the wheel"
  extends WheelTerrain.Components.PartialWheel;
  input Real soil[${S}] "the soil.* parameters under the wheel, table order (Functions.Index.Soil)";
equation
  pk = cat(1, p[1:${SOIL_FIRST}], soil, p[${SOIL_AFTER}:${N}]);
  annotation(Documentation(info="<html><p>The contact of Wheel with the soil rows (soil.*) of its parameters given by the input <code>soil</code>, e.g. a terrain's soil at the wheel's position (Wheels.PlanarWheel: Terrain.soil). A change of soil is not an event here; MapWheel writes the terrain map's rule as an equation so that the tool meets a patch's edges as events.</p></html>",
    revisions="<html><ul><li>${version}: first version.</li></ul></html>"));
end SoilWheel;
