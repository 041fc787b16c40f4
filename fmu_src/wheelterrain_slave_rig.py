"""pythonfmu slave of SingleWheelRig.fmu: the paper's single-wheel test rig.

Thin on purpose: the variables, checks and state live in wheelterrain.fmu.slaves, the rig's
equations in wheelterrain.model.rig (bundled in the FMU's resources/). Unique module name (pythonfmu
issue #228).
"""

from pythonfmu import DefaultExperiment, Fmi2Slave

from wheelterrain.fmu.slaves import RigCore


class SingleWheelRig(Fmi2Slave):
    description = ("Single-wheel test rig: carriage at rim_speed/(1 + s), speed-controlled wheel "
                   "motor, vertical motion of the wheel under the rig's load")
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=0.001)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = RigCore(self)

    def exit_initialization_mode(self):
        self.core.initialize()

    def do_step(self, current_time, step_size):
        return self.core.do_step(current_time, step_size)

    def _get_fmu_state(self):
        return self.core.get_state()

    def _set_fmu_state(self, state):
        self.core.set_state(state)
