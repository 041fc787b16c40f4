block Wheel "The WheelTerrain FMU's contact as a block (its model exchange): the wheel's angle and the soil's memory its states"
  extends WheelTerrain.Components.PartialWheel;
  parameter Real p[${N}] = WheelTerrain.Data.rashidPatch
    "the parameters in table order (WheelTerrain.Data, Records.parameterVector)";
equation
  pk = p;
end Wheel;
