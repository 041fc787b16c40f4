package Ground "The terrain's shape: its height and slope at a horizontal position (Terrain's default functions)"
  function height "The terrain's height at a horizontal position: flat, a plane or a profile"
    extends WheelTerrain.Functions.Interfaces.Height;
    input WheelTerrain.Types.Ground ground = WheelTerrain.Types.Ground.flat "the shape";
    input Modelica.Units.SI.Angle slope = 0 "the plane's inclination, rising toward +x (ground = plane)";
    input Modelica.Units.SI.Length profile[:, 2] = {{0, 0}, {1, 0}} "x [m] and height [m] of the profile's points, x rising (ground = profile)";
  protected
    Integer k = WheelTerrain.Functions.Ground.segment(x, profile);
    Real share = WheelTerrain.Functions.Ground.share(x, profile, k);
  algorithm
    h := if ground == WheelTerrain.Types.Ground.plane then x*tan(slope) elseif ground == WheelTerrain.Types.Ground.profile then profile[k, 2] + share*(profile[k + 1, 2] - profile[k, 2]) else 0;
    annotation(Documentation(info="<html><p>flat: 0; plane: x&middot;tan(slope); profile: linear between the table's points, the first or last point's height beyond them.</p></html>"));
  end height;

  function slope "The terrain's inclination at a horizontal position, rising toward +x: flat, a plane or a profile"
    extends WheelTerrain.Functions.Interfaces.Slope;
    input WheelTerrain.Types.Ground ground = WheelTerrain.Types.Ground.flat "the shape";
    input Modelica.Units.SI.Angle slope = 0 "the plane's inclination (ground = plane)";
    input Modelica.Units.SI.Length profile[:, 2] = {{0, 0}, {1, 0}} "x [m] and height [m] of the profile's points, x rising (ground = profile)";
  protected
    Integer k = WheelTerrain.Functions.Ground.segment(x, profile);
    Real inside = if x > profile[1, 1] and x < profile[size(profile, 1), 1] then 1 else 0;
  algorithm
    angle := if ground == WheelTerrain.Types.Ground.plane then slope elseif ground == WheelTerrain.Types.Ground.profile then inside*atan((profile[k + 1, 2] - profile[k, 2])/(profile[k + 1, 1] - profile[k, 1])) else 0;
    annotation(Documentation(info="<html><p>flat: 0; plane: slope; profile: the inclination of the segment under x (level beyond the table). At a profile's point the segment after it counts.</p></html>"));
  end slope;

  function segment "The profile's segment holding x: k with profile[k, 1] <= x < profile[k + 1, 1] (the first or last segment beyond the table)"
    input Modelica.Units.SI.Length x "horizontal position";
    input Modelica.Units.SI.Length profile[:, 2] "x [m] and height [m] of the profile's points, x rising";
    output Integer k "the segment's first point";
  algorithm
    assert(size(profile, 1) >= 2, "Terrain: a profile needs at least two points");
    k := 1;
    for j in 2:size(profile, 1) - 1 loop
      k := if x >= profile[j, 1] then j else k;
    end for;
  end segment;

  function share "Where x lies in the profile's segment k, clipped to [0, 1] (level beyond the table)"
    input Modelica.Units.SI.Length x "horizontal position";
    input Modelica.Units.SI.Length profile[:, 2] "x [m] and height [m] of the profile's points, x rising";
    input Integer k "the segment";
    output Modelica.Units.SI.DimensionlessRatio share "0 at its first point, 1 at its last";
  algorithm
    assert(profile[k + 1, 1] > profile[k, 1], "Terrain: the profile's x must rise from point to point");
    share := min(1, max(0, (x - profile[k, 1])/(profile[k + 1, 1] - profile[k, 1])));
  end share;
  annotation(Documentation(info="<html><p>Written in Modelica (not generated): the terrain's geometry, which the Python model does not have (its rover takes the slope as an input). tests/test_modelica.py checks them against numpy's interpolation.</p></html>"));
end Ground;
