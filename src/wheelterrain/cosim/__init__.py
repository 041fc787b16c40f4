"""Co-simulation with the FMUs and the rover: the C1-C4 master and the paper comparison
(:mod:`.master`), SSP files and the SSP engines (:mod:`.ssp`), parallel parameter sweeps
(:mod:`.sweep`), the energy ledgers (:mod:`.energy`), and the rover: its engine in process
(:mod:`.rover`), the ruts along its tracks (:mod:`.ruts`), its limits (:mod:`.rover_limits`),
its scenarios (:mod:`.rover_scenarios`) and its FMU engines (:mod:`.rover_fmus`)."""

# The SSP engines a Rover.ssp or a C1-C4 SSP runs in, each with the Python module that drives
# it (OMSimulator: its command-line tool). Here, not in rover_fmus, so the command line can
# list them without importing fmpy.
SSP_ENGINES = {"libcosim": "libcosimpy", "ecos": "ecospy", "omsimulator": None,
               "fmpy-ssp": "fmpy"}
ROVER_ENGINES = ("in-process", "fmus", *SSP_ENGINES)
"""What runs the rover: in process, our master on the FMUs, or the Rover SSP in an SSP engine
(the run layer's registry, :mod:`wheelterrain.run.rover`, has an entry for each)."""
ROVER_CONTROLLERS = ("speed", "mpc")
"""What drives the rover's wheels: the four speed loops, or the slip NMPC per wheel."""
