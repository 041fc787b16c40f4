"""pythonfmu slave of RoverChassis.fmu: the rover's chassis on four driven wheels.

Thin on purpose: the variables, checks and state live in wheelterrain.fmu.slaves, the chassis'
equations in wheelterrain.model.rover (bundled in the FMU's resources/). Unique module name
(pythonfmu issue #228).
"""

from pythonfmu import DefaultExperiment, Fmi2Slave

from wheelterrain.fmu.slaves import RoverCore


class RoverChassis(Fmi2Slave):
    description = ("Rover chassis in the vertical plane of travel (position, heave, pitch) on "
                   "four rigidly mounted, speed-controlled wheels; per wheel the states a "
                   "WheelTerrain instance needs, its forces as inputs")
    license = "MIT"
    # 1 s: standing alone on fixed wheel loads the chassis balances like an inverted pendulum
    # (its centre of mass above the axles); over 10 s rounding grew into a 0.19 m heave
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=0.001)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = RoverCore(self)

    def exit_initialization_mode(self):
        self.core.initialize()

    def do_step(self, current_time, step_size):
        return self.core.do_step(current_time, step_size)

    def _get_fmu_state(self):
        return self.core.get_state()

    def _set_fmu_state(self, state):
        self.core.set_state(state)
