package Types "Enumerations for the components' options"
  type Ground = enumeration(
      flat "level ground at height 0",
      plane "a plane through the origin rising at a constant slope toward +x",
      profile "heights over x from a table, linear between its points and level beyond them")
    "The terrain's shape (WheelTerrain.Terrain.ground)";
${ENUMERATIONS}
  annotation(Documentation(info="<html><p>Enumerations of the components' options: the terrain's shape, and every option of the parameter table (the records' option fields, Records.Options). Records.parameterVector turns them into the table's integer codes, which the functions, the FMUs and the CLI take (one list of names, the table's).</p></html>",
    revisions="<html><ul><li>${version}: Ground (the inner Terrain's shape); the table's options as enumerations.</li></ul></html>"));
end Types;
