"""pythonfmu slave of Terrain.fmu: a terrain map's query point, the soil at its position.

Thin on purpose: the variables, checks and state live in wheelterrain.fmu.slaves, the map in
wheelterrain.model.ground (bundled in the FMU's resources/). Unique module name (pythonfmu
issue #228).
"""

from pythonfmu import DefaultExperiment, Fmi2Slave

from wheelterrain.fmu.slaves import GroundCore


class Terrain(Fmi2Slave):
    description = ("Terrain map along a path: one soil with a patch of another; its output is "
                   "the soil at the query point's position (the ground.* inputs of a "
                   "WheelTerrain with soil_from_inputs)")
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
