"""Slip control on the CasADi twin: the NMPC (:mod:`.mpc`) and its closed loop against the FMU
plant or the same Functions in process, with the soil estimator (:mod:`.closed_loop`)."""
