package Types "Enumerations for the components' options"
  type Ground = enumeration(
      flat "level ground at height 0",
      plane "a plane through the origin rising at a constant slope toward +x",
      profile "heights over x from a table, linear between its points and level beyond them")
    "The terrain's shape (WheelTerrain.Terrain.ground)";
  annotation(Documentation(info="<html><p>Enumerations of the components' options. The parameter records keep the table's integer codes (Records, UsersGuide.NameMap): they are the FMUs' parameters and the CLI's, one list of names for every face.</p></html>",
    revisions="<html><ul><li>${version}: Ground (the inner Terrain's shape).</li></ul></html>"));
end Types;
