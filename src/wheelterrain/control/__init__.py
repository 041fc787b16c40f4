"""Slip control on the CasADi twin: the NMPC (:mod:`.mpc`), its closed loop against the FMU
plant or the same Functions in process, with the soil estimator (:mod:`.closed_loop`), and the
NMPC per wheel on the rover (:mod:`.rover_mpc`)."""
