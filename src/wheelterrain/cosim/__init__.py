"""Co-simulation with the FMUs: the C1-C4 master and the paper comparison (:mod:`.master`),
SSP files (:mod:`.ssp`) and parallel parameter sweeps (:mod:`.sweep`)."""
