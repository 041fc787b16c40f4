partial block PartialWheel "The WheelTerrain FMU's contact as a block (its model exchange), its parameter vector pk given by the block that extends it"
  replaceable parameter WheelTerrain.Records.Presets.RashidPatch parameters
    constrainedby WheelTerrain.Records.Parameters
    "the wheel and the contact model as a record (a preset, or your own values), p by default"
    annotation(choicesAllMatching=true);
  parameter Real p[${N}] = WheelTerrain.Records.parameterVector(parameters)
    "the parameters in table order: the record's, or a vector of WheelTerrain.Data given instead";
  Real pk[${N}] "the parameters the contact takes, in table order (p, its soil rows the extending block's)";
  replaceable function contactFunction = WheelTerrain.Functions.contact
    constrainedby WheelTerrain.Functions.Interfaces.Contact
    "the contact: Functions.contact (generated, the default) or Functions.External.contact (CasADi's C)";
  input Real sinkage(unit="m") "of the contact circle below the undisturbed surface";
  input Real sinkage_rate(unit="m/s") "d(sinkage)/dt";
  input Real wheel_speed(unit="rad/s") "the wheel's angular velocity";
  input Real carriage_speed(unit="m/s") "the axle's forward speed";
  input Real slip_angle(unit="rad")
    "between the wheel's heading and its velocity, + moving toward its left (0: driven straight)";
  input Real yaw_rate(unit="rad/s")
    "the wheel's yaw rate about the vertical, + counter-clockwise from above (0: it does not yaw)";
  Real rolling(unit="1")
    "-1 rolling backward (omega*R + V < 0: both speeds <= 0 but near rest): the mirror image of rolling forward; else 1";
  Real turn_slip(unit="rad/m") = if abs(yaw_rate) > 0 then rolling*yaw_rate/max(rolling*carriage_speed, ${SPEED_FLOOR}) else 0
    "the turn slip yaw_rate/carriage_speed, the curvature of the wheel's path";
  output Real normal_force(unit="N") "the soil's force on the wheel, up";
  output Real drawbar_pull(unit="N") "the soil's net force on the wheel, forward";
  output Real torque(unit="N.m") "the torque the soil resists the wheel's turning with";
  output Real slip(unit="1") "the model's slip along the rolling: traction driving, skid braking (-1 locked)";
  output Real rut_left(unit="m") "the rut the wheel leaves";
  output Real rut_pressure_left(unit="Pa") "the pressure the wheel pressed that rut to (its soil.rut_pressure for the next wheel)";
  Real wheel_angle(unit="rad", start=0, fixed=true) "the grouser ripple's phase";
  Real plastic_sinkage(unit="m", start=0, fixed=true) "the deepest the wheel has pressed the soil under it";
  output Real lateral_force(unit="N") "the soil's force on the wheel along its axle, + to its left";
  output Real aligning_moment(unit="N.m") "the lateral stresses' moment about the vertical through the centre, + counter-clockwise from above";
  output Real turning_moment(unit="N.m") "the soil's whole moment about that vertical (M_z): aligning_moment and the longitudinal shear's across the width";
  output Real overturning_moment(unit="N.m") "the lateral stresses' moment about the heading axis x through the centre (M_x), + by the right-hand rule";
  output Real y[${CONTACT_ROWS}] "every output of Functions.contact, Functions.Index order (rolling backward: the mirror image's)";
  output Real y_lateral[${LATERAL_ROWS}] "every output of Functions.lateralMemory, Functions.Index.Lateral order";
  Real share(unit="1")
    "the direction of rolling's share of the contact: 1, but within the slip's speed floor of the turn of rolling, where the wheel rolling the other way takes the rest (Functions.turningWeight, the FMU's blend)";
  Real y_turned[${CONTACT_ROWS}] "the contact of the wheel rolling the other way (used where share < 1; else y)";
  Real y_lateral_turned[${LATERAL_ROWS}] "its lateral contact (used where share < 1; else y_lateral)";
  Real turn_slip_turned(unit="rad/m") "its turn slip (0 where out of its range, as in the FMU)";
equation
  // an equation, not a binding: rumoca 0.10 miscounts the equations where a binding's call is
  // multiplied into other calls' arguments
  rolling = WheelTerrain.Functions.rollingSign(wheel_speed, carriage_speed, pk);
  der(wheel_angle) = wheel_speed;
  slip = WheelTerrain.Functions.slipFromSpeeds(rolling*wheel_speed, rolling*carriage_speed, pk);
  assert(slip >= -1 and slip <= 1, "Wheel: the slip left the model's range [-1, 1] (the wheel turning against its axle's motion beyond ${SLIP_SPEED_FLOOR} m/s of rest: |omega*R_ref| + |v|)");
  // backward, the grousers of the mirror image: the wheel's angle and the ripple's phase negated
  // (mirroredGrousers, the FMU's rule)
  y = contactFunction(sinkage, sinkage_rate, slip, rolling*wheel_angle, plastic_sinkage, rolling*carriage_speed,
    cat(1, pk[1:${PHASE_BEFORE}], {rolling*pk[${PHASE}]}, pk[${PHASE_AFTER}:${N}]));
  // within the slip's speed floor of the turn of rolling the contact is the blend of both
  // directions (the FMU's, functions.turning_weight): the other's only evaluated there
  share = noEvent(if rolling > 0 then WheelTerrain.Functions.turningWeight(wheel_speed, carriage_speed, pk)
    else 1 - WheelTerrain.Functions.turningWeight(wheel_speed, carriage_speed, pk));
  y_turned = noEvent(if share < 1 then contactFunction(sinkage, sinkage_rate, -slip, -rolling*wheel_angle, plastic_sinkage,
    -rolling*carriage_speed, cat(1, pk[1:${PHASE_BEFORE}], {-rolling*pk[${PHASE}]}, pk[${PHASE_AFTER}:${N}])) else y);
  der(plastic_sinkage) = share*y[WheelTerrain.Functions.Index.plastic_rate] + (1 - share)*y_turned[WheelTerrain.Functions.Index.plastic_rate];
  normal_force = share*y[WheelTerrain.Functions.Index.normal_force] + (1 - share)*y_turned[WheelTerrain.Functions.Index.normal_force];
  drawbar_pull = rolling*(share*y[WheelTerrain.Functions.Index.drawbar_pull] - (1 - share)*y_turned[WheelTerrain.Functions.Index.drawbar_pull]);
  torque = rolling*(share*y[WheelTerrain.Functions.Index.torque] - (1 - share)*y_turned[WheelTerrain.Functions.Index.torque]);
  rut_left = share*y[WheelTerrain.Functions.Index.rut_left] + (1 - share)*y_turned[WheelTerrain.Functions.Index.rut_left];
  rut_pressure_left = share*y[WheelTerrain.Functions.Index.rut_pressure_left] + (1 - share)*y_turned[WheelTerrain.Functions.Index.rut_pressure_left];
  assert(abs(yaw_rate) <= ${TURN_SLIP_LIMIT}*max(rolling*carriage_speed, 0), "Wheel: |yaw_rate|/carriage_speed beyond ${TURN_SLIP_LIMIT} rad/m, the lateral contact's range (a wheel yawing on the spot or at rest is outside the model)");
  y_lateral = WheelTerrain.Functions.lateralMemory(sinkage, slip, rolling*slip_angle, turn_slip, plastic_sinkage,
    y[WheelTerrain.Functions.Index.mean_pressure], pk);
  turn_slip_turned = noEvent(if abs(yaw_rate) > ${TURN_SLIP_LIMIT}*max(-rolling*carriage_speed, 0) then 0
    else -rolling*yaw_rate/max(-rolling*carriage_speed, ${SPEED_FLOOR}));
  y_lateral_turned = noEvent(if share < 1 then WheelTerrain.Functions.lateralMemory(sinkage, -slip, -rolling*slip_angle, turn_slip_turned,
    plastic_sinkage, y_turned[WheelTerrain.Functions.Index.mean_pressure], pk) else y_lateral);
  lateral_force = share*y_lateral[WheelTerrain.Functions.Index.Lateral.lateral_force] + (1 - share)*y_lateral_turned[WheelTerrain.Functions.Index.Lateral.lateral_force];
  aligning_moment = rolling*(share*y_lateral[WheelTerrain.Functions.Index.Lateral.aligning_moment] - (1 - share)*y_lateral_turned[WheelTerrain.Functions.Index.Lateral.aligning_moment]);
  turning_moment = rolling*(share*y_lateral[WheelTerrain.Functions.Index.Lateral.turning_moment] - (1 - share)*y_lateral_turned[WheelTerrain.Functions.Index.Lateral.turning_moment]);
  overturning_moment = share*y_lateral[WheelTerrain.Functions.Index.Lateral.overturning_moment] + (1 - share)*y_lateral_turned[WheelTerrain.Functions.Index.Lateral.overturning_moment];
  annotation(Documentation(info="<html><p>The WheelTerrain FMU's model exchange as a block: the same inputs, the same contact, its states wheel_angle and plastic_sinkage; at a slip angle and a yaw rate, the lateral force and the moments of the soil with memory (Functions.lateralMemory, the FMU's own, the grouser-period mean). Rolling backward (omega*R + V &lt; 0: both speeds &lt;= 0 but within the slip's speed floor of rest) is the mirror image of rolling forward, as in the FMU: the contact of the speeds' magnitudes, the slip angle, the yaw rate, the wheel's angle and the ripple's phase negated, and the forces along x, the torque and the moments about the vertical negated (<code>rolling</code>, Functions.rollingSign); within the slip's speed floor of the turn of rolling (omega*R + V = 0) the contact is the blend of the two directions, as in the FMU (<code>share</code>, Functions.turningWeight), so a driven vehicle stops and reverses; a wheel turning against its axle's motion beyond that floor stops the simulation on the slip's assert. Wheel gives it one parameter vector, MapWheel the soil of a terrain map at the wheel's position.</p></html>"));
end PartialWheel;
