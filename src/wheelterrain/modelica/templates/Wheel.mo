block Wheel "The WheelTerrain FMU's contact as a block (its model exchange): the wheel's angle and the soil's memory its states"
  extends WheelTerrain.Components.PartialWheel;
equation
  pk = p;
end Wheel;
