"""pythonfmu slave of WheelTerrain.fmu: the wheel-soil contact forces of the wheelterrain model.

Thin on purpose: the variables, checks and state live in wheelterrain.fmu.slaves, the physics in
wheelterrain.model.contact (bundled in the FMU's resources/). The module name is unique to this FMU
(pythonfmu issue #228: two FMUs whose slave modules share a name cannot share a process).
"""

from pythonfmu import DefaultExperiment, Fmi2Slave

from wheelterrain.fmu.slaves import TerrainCore


class WheelTerrain(Fmi2Slave):
    description = ("Wheel-terrain contact of a rigid grousered wheel on loose soil: Reece "
                   "pressure-sinkage with grouser ripple, Wong-Reece stress, Janosi/Wong shear")
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=0.001)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = TerrainCore(self)

    def exit_initialization_mode(self):
        self.core.initialize()

    def do_step(self, current_time, step_size):
        return self.core.do_step(current_time, step_size)

    def _get_fmu_state(self):
        return self.core.get_state()

    def _set_fmu_state(self, state):
        self.core.set_state(state)
