"""pythonfmu slave of Terrain.fmu: a terrain map's query point, the soil at its position.

Thin on purpose: the variables, checks and state live in wheelterrain.fmu.slaves, the map in
wheelterrain.model.ground (bundled in the FMU's resources/). Unique module name (pythonfmu
issue #228).
"""

from pythonfmu import DefaultExperiment, Fmi2Slave

from wheelterrain.fmu.slaves import GroundCore


class Terrain(Fmi2Slave):
    description = ("Terrain of one track: the soil map along the path (one soil with a patch "
                   "of another) at its two query points (the ground.* inputs of a WheelTerrain "
                   "with soil_from_inputs), and the rut profile it keeps as its state: the "
                   "deepest rut each wheel left in each terrain.cell of the track's last 256, "
                   "which the wheel behind meets (q*.rut_met); saved and restored with the FMU "
                   "state, laid only by co-simulation steps")
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.002)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = GroundCore(self)

    def exit_initialization_mode(self):
        self.core.initialize()

    def do_step(self, current_time, step_size):
        return self.core.do_step(current_time, step_size)

    def _get_fmu_state(self):
        return self.core.get_state()

    def _set_fmu_state(self, state):
        self.core.set_state(state)
