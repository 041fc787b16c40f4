"""What runs inside the FMUs: the behaviour behind the thin pythonfmu slave scripts in fmu_src/.

The scripts only declare ``class WheelTerrain(Fmi2Slave)`` / ``class SingleWheelRig(Fmi2Slave)``
(pythonfmu finds the class by that literal pattern) and delegate here. No physics lives here
either: forces come from :mod:`wheelterrain.model.contact`, the rig from
:mod:`wheelterrain.model.rig`.

What this layer adds around pythonfmu (its gaps: see fmu_src/README.md):
- every variable is declared once in a :class:`Var` list that both the slave and the
  modelDescription post-processor (:mod:`wheelterrain.fmu.build_pythonfmu`) read, so names,
  units, ranges and descriptions cannot drift apart;
- bad parameters and inputs never raise into pythonfmu (an exception there is fmi2Fatal): the
  setter stores the value, logs an error naming the variable and its valid range, and the next
  doStep refuses with a logged reason (pythonfmu maps a refused step to fmi2Discard);
- get/set FMU state covers the internal state (wheel angle, rig states, error flags), not only
  the registered variables.
"""

from __future__ import annotations

import gc
import math
import sys
import weakref
from collections.abc import Callable
from functools import partial
from pathlib import Path
from types import MappingProxyType

from wheelterrain import compiled as native
from wheelterrain.errors import ParameterError
from wheelterrain.fmu import functions as fmu_model
from wheelterrain.fmu.variables import VARIABLES, Var, soil_from_ground, terrain_variables
from wheelterrain.model import rig
from wheelterrain.parameters import BY_NAME, GROUND_TABLE, ROVER_TABLE, TABLE


def compiled_or_vm(fn, resources: str | None = None):
    """(evaluate, how): ``fn`` as the compiled C that `wheelterrain build` shipped in
    resources/wheelterrain/_compiled (same CasADi Function, generated and compiled; ~10 us per
    call instead of ~70), else the CasADi VM. A library is used only if its fingerprint matches
    ``fn`` in this process (a Python host may have imported its own wheelterrain first)."""
    places = [Path(resources) / "wheelterrain" / "_compiled"] if resources else []
    places.append(Path(__file__).resolve().parents[1] / "_compiled")  # the package root's
    for place in places:
        library = place / f"{fn.name()}.so"
        if library.is_file():
            try:
                return native.CompiledFunction(library, fn), "compiled C"
            except (OSError, native.CompileError):
                continue  # another platform or another version: the VM gives the same numbers

    arrays = native.vm_arrays(fn)  # a list of outputs, also for a Function with one output

    def vm(*args):
        return [x.tolist() if x.size > 1 else float(x[0]) for x in arrays(*args)]

    return vm, "CasADi VM"


# --------------------------------------------------------------------------------------------
# Several instances in one process, each with its own unzipped resources
#
# pythonfmu puts an instance's resources/ first on sys.path, so the bundled wheelterrain is
# imported from the first instance's unzip folder and stays imported. A host that extracts each
# FMU to a temporary folder and deletes it after the run (fmpy.simulate_fmu, libcosim, ecos)
# leaves the package pointing at a folder that is gone: the next instance could neither read
# the presets nor import a module not yet loaded. So every instance puts its own bundled copy
# first in the __path__ of each loaded wheelterrain package (a package's __path__ may list
# several folders; one that is gone is dropped), and the package reads its data from the first
# folder there that exists (wheelterrain.package_folder).


def follow_resources(resources: str | None) -> None:
    """Make this instance's bundled package (``resources``/wheelterrain) the first place the
    imported wheelterrain package loads modules and data from. Only where the package itself
    was imported from an FMU's resources (a Python host with its own wheelterrain keeps it)."""
    import wheelterrain

    if not resources:
        return
    own = Path(resources) / "wheelterrain"
    if not own.is_dir():
        return
    if not all(not Path(entry).is_dir() or (Path(entry).parent / "slavemodule.txt").is_file()
               for entry in wheelterrain.__path__):
        return  # the host's own installed or checked-out package: it stays
    for name, module in list(sys.modules.items()):
        path = getattr(module, "__path__", None)
        if path is None or not (name == "wheelterrain" or name.startswith("wheelterrain.")):
            continue
        if not isinstance(path, list):
            continue  # a namespace package: Python recomputes its path from sys.path itself
        folder = own.joinpath(*name.split(".")[1:])
        kept = [entry for entry in path if entry != str(folder) and Path(entry).is_dir()]
        path[:] = [str(folder), *kept]


# --------------------------------------------------------------------------------------------
# Instance lifetime: CasADi objects must be gone before the interpreter is finalised
#
# In a C host, pythonfmu finalises the interpreter it started from a static destructor of its
# library, at process exit, after CasADi's own static destructors have run. A CasADi Function
# still referenced from Python then is destroyed against CasADi's destroyed statics: "pure
# virtual method called", the host aborts (exit 134) after a clean run. So when the last
# instance in the process is freed (fmi2FreeInstance drops pythonfmu's reference; the cores
# hold their slaves weakly, so that frees them), the package's caches of CasADi objects are
# emptied while CasADi is still whole. Only where pythonfmu started the interpreter: a Python
# host (fmpy) finalises its interpreter before any static destructor, and keeps its caches.

_live_instances = 0


def _instance_created(slave) -> None:
    global _live_instances
    _live_instances += 1
    weakref.finalize(slave, _instance_freed)


def _instance_freed() -> None:
    global _live_instances
    _live_instances -= 1
    if _live_instances == 0 and embedded_interpreter():
        release_casadi_objects()


def embedded_interpreter() -> bool:
    """True when this interpreter was started by a C host's FMU library, not by a ``python``
    command (``sys.orig_argv`` is empty only for an interpreter embedded with Py_Initialize)."""
    return not sys.orig_argv


def release_casadi_objects() -> None:
    """Empty every cache of the wheelterrain modules loaded (the CasADi Functions, their
    compiled libraries) and collect what they referenced. They are rebuilt on next use."""
    for name, module in list(sys.modules.items()):
        if name == "wheelterrain" or name.startswith("wheelterrain."):
            for value in list(vars(module).values()):
                if callable(getattr(value, "cache_clear", None)):
                    value.cache_clear()
    gc.collect()


# --------------------------------------------------------------------------------------------
# The slave behaviours


class _Core:
    """Shared plumbing: values by name, registration with pythonfmu, deferred error reporting."""

    model_name = ""

    def __init__(self, slave, variables: list[Var]) -> None:
        # weakly: the slave owns this core, and nothing of ours may keep the slave alive once
        # pythonfmu drops it (see _instance_created)
        self.slave = weakref.proxy(slave)
        _instance_created(slave)
        self.vars = {v.name: v for v in variables}
        self.values: dict[str, float] = {}
        self.errors: dict[str, str] = {}
        self.initialized = False  # initialisation mode has been left (doStep is legal)
        for v in variables:
            if v.start is not None:
                self.values[v.name] = v.start
        self._register(variables)
        self._guard_references()

    # --- registration ---------------------------------------------------------------------
    def _register(self, variables: list[Var]) -> None:
        from pythonfmu import Boolean, Fmi2Causality, Fmi2Variability, Integer, Real

        kinds = {"Real": Real, "Integer": Integer, "Boolean": Boolean}
        for v in variables:
            causality = getattr(Fmi2Causality, v.causality)
            variability = (Fmi2Variability.tunable if v.causality == "parameter"
                           else Fmi2Variability.continuous if v.type == "Real"
                           else Fmi2Variability.discrete)
            getter = self._getter(v.name)
            setter = None if v.causality == "output" else self._setter(v.name)
            var = kinds[v.type](v.name, causality=causality, description=v.description,
                                variability=variability, getter=getter, setter=setter)
            self.slave.register_variable(var, nested=False)

    def _getter(self, name: str) -> Callable[[], float]:
        def get():
            if self.vars[name].causality != "output":
                return self.values.get(name, math.nan)
            self.refresh()
            # an output the model has never computed (every evaluation so far was refused) is
            # NaN, not a plausible-looking 0 in the host's results
            value = self.values.get(name, math.nan)
            if name in fmu_model.UNDEFINED_OUTPUTS and value != value:
                # as the native flavour, whose fmi2GetReal also returns fmi2Warning (a
                # pythonfmu getter cannot: fmu_src/README.md)
                self.log_warning(f"fmi2GetReal: {name} is undefined at this operating point "
                                 f"(NaN): {self.vars[name].description}")
            return value
        return get

    def _setter(self, name: str) -> Callable[[float], None]:
        def put(value):
            self.values[name] = value
            self.validate(name, value)
            self.dirty = True
        return put

    dirty = True

    # --- checking ---------------------------------------------------------------------------
    def validate(self, name: str, value) -> None:
        """Record (and log, at error level) what is wrong with ``value``; forget an old error
        once the value is valid again."""
        message = self.problem(name, value)
        if message is None:
            self.errors.pop(name, None)
        else:
            self.errors[name] = message
            self.log_error(message)

    def problem(self, name: str, value) -> str | None:
        """What is wrong with ``value``, or None. Table parameters (terrain and rig) are checked
        by their Parameter row; inputs by the range their Var declares."""
        v = self.vars[name]
        if v.type == "Boolean":
            return None
        try:
            if name in _PARAMETERS:
                _PARAMETERS[name].check(value)
            else:
                self.check_value(name, float(value))
        except ParameterError as exc:
            return str(exc)
        return None

    def check_value(self, name: str, value: float) -> None:
        v = self.vars[name]
        if not math.isfinite(value):
            raise ParameterError(name, value, f"must be finite; valid range [{v.min:g}, "
                                 f"{v.max:g}] {v.unit}")
        if v.min is not None and not v.min <= value <= v.max:
            raise ParameterError(name, value, f"is out of range; valid range [{v.min:g}, "
                                 f"{v.max:g}] {v.unit}")

    def log_error(self, message: str) -> None:
        from pythonfmu.enums import Fmi2Status
        self.slave.log(f"{self.model_name}: {message}", Fmi2Status.error)

    def log_warning(self, message: str) -> None:
        from pythonfmu.enums import Fmi2Status
        self.slave.log(f"{self.model_name}: {message}", Fmi2Status.warning)

    # --- value references the FMU does not have --------------------------------------------
    # pythonfmu 0.7 turns the KeyError or TypeError of an unknown (or wrongly typed) value
    # reference into fmi2Fatal, frees the Python instance, and the next call crashes the host.
    # Every get/set of the slave goes through these (_guard_references): the bad references
    # are logged as an error (nothing is set for them, NaN/0/false is returned for them), the
    # good ones are served.
    _EMPTY = MappingProxyType({"Real": math.nan, "Integer": 0, "Boolean": False})

    def _guard_references(self) -> None:
        """Route the slave's get_/set_ Real, Integer and Boolean through the checks below (as
        instance attributes, which pythonfmu's calls by name find first)."""
        self._valid = {kind: frozenset(vr for vr, var in self.slave.vars.items()
                                       if type(var).__name__ == kind) for kind in self._EMPTY}
        for kind in self._EMPTY:
            # the class's functions, not bound methods: a bound method stored on the slave
            # would make a reference cycle and keep the slave alive after fmi2FreeInstance
            fetch = partial(getattr(self.slave.__class__, f"get_{kind.lower()}"), self.slave)
            store = partial(getattr(self.slave.__class__, f"set_{kind.lower()}"), self.slave)
            setattr(self.slave, f"get_{kind.lower()}", partial(self.get_checked, fetch, kind))
            setattr(self.slave, f"set_{kind.lower()}", partial(self.set_checked, store, kind))

    def _bad_references(self, kind: str, vrs) -> list[int]:
        valid = self._valid[kind]
        return [] if valid.issuperset(vrs) else [vr for vr in vrs if vr not in valid]

    def get_checked(self, fetch: Callable, kind: str, vrs) -> list:
        bad = self._bad_references(kind, vrs)
        if not bad:
            return fetch(vrs)
        self.log_error(f"fmi2Get{kind}: no {kind} variable with value reference "
                       f"{', '.join(map(str, bad))}; {self._EMPTY[kind]} returned for it")
        good = [vr for vr in vrs if vr not in bad]
        values = dict(zip(good, fetch(good) if good else [], strict=True))
        return [values.get(vr, self._EMPTY[kind]) for vr in vrs]

    def set_checked(self, store: Callable, kind: str, vrs, values) -> None:
        bad = self._bad_references(kind, vrs)
        if bad:
            self.log_error(f"fmi2Set{kind}: no {kind} variable with value reference "
                           f"{', '.join(map(str, bad))}; not set")
            pairs = [(vr, x) for vr, x in zip(vrs, values, strict=True) if vr not in bad]
            vrs, values = [vr for vr, _ in pairs], [x for _, x in pairs]
        if vrs:
            store(vrs, values)

    def step_allowed(self, t: float, h: float) -> bool:
        """The API checks of fmi2DoStep, logged as errors when they fail: initialisation has
        ended, and the step's time and size are finite with h > 0 (a bad step made the state
        NaN with fmi2OK). pythonfmu maps the refusal to fmi2Discard."""
        if not self.initialized:
            self.log_error("fmi2DoStep: illegal call sequence: initialisation mode has not been "
                           "left (call fmi2ExitInitializationMode first)")
            return False
        if not (math.isfinite(t) and math.isfinite(h) and h > 0):
            self.log_error(f"fmi2DoStep: communication step {h:g} at t = {t:g} must be finite "
                           "and > 0")
            return False
        return True

    def _settings_invalid(self) -> bool:
        """A set value is invalid (its error names it): the model is not evaluated until it is
        set right, and the last valid outputs stay."""
        return any(name != OPERATING_POINT for name in self.errors)

    def _operating_point(self, problem: str | None) -> bool:
        """Record what the model says of the current operating point: ``problem`` (logged, and
        the next step refused) or None (clears an earlier one). True if there is a problem."""
        self.errors.pop(OPERATING_POINT, None)
        if problem:
            self.errors[OPERATING_POINT] = problem
            self.log_error(problem)
        return bool(problem)

    def refuse_if_invalid(self) -> bool:
        """True if the instance may step; else log every reason and refuse."""
        if not self.errors:
            return True
        for message in self.errors.values():
            self.log_error(f"step refused: {message}")
        return False

    # --- state --------------------------------------------------------------------------------
    def get_state(self) -> dict:
        return {"values": dict(self.values), "errors": dict(self.errors),
                "internal": self.internal_state()}

    def set_state(self, state: dict) -> None:
        self.values = dict(state["values"])
        self.errors = dict(state["errors"])
        self.set_internal_state(state["internal"])
        self.dirty = True

    def internal_state(self) -> dict:  # pragma: no cover - overridden
        return {}

    def set_internal_state(self, state: dict) -> None:  # pragma: no cover - overridden
        pass

    def refresh(self) -> None:  # pragma: no cover - overridden
        pass


class TerrainCore(_Core):
    """WheelTerrain: contact forces from the core model, fed by the wheel's states."""

    model_name = "WheelTerrain"

    def __init__(self, slave) -> None:
        resources = getattr(slave, "resources", None)
        follow_resources(resources)
        dynamic, quasi, memory = fmu_model.terrain_functions()
        self.dynamic, self.evaluator = compiled_or_vm(dynamic, resources)
        self.quasi_static, _ = compiled_or_vm(quasi, resources)
        self.memory, _ = compiled_or_vm(memory, resources)
        super().__init__(slave, terrain_variables())
        self.angle = 0.0
        self.plastic = 0.0  # the plastic sinkage: the soil's memory under the wheel

    def internal_state(self) -> dict:
        return {"angle": self.angle, "plastic": self.plastic}

    def set_internal_state(self, state: dict) -> None:
        self.angle = float(state["angle"])
        self.plastic = float(state["plastic"])

    def _inputs_and_parameters(self) -> tuple[list, list]:
        v = self.values
        u = [float(v[name]) for name in fmu_model.TERRAIN_INPUTS]
        p = [float(v[prm.name]) for prm in TABLE]
        if v["soil_from_inputs"]:
            p = soil_from_ground(p, v)
        return u, p

    def _advance(self, h: float) -> None:
        """The states over a step of ``h`` with the inputs held (fmi2_native.c's model_step)."""
        self.angle += float(self.values["wheel_speed"]) * h
        if not self.values["quasi_static"]:
            u, p = self._inputs_and_parameters()
            self.plastic = float(self.memory(u, self.plastic, p, h)[0])

    def refresh(self) -> None:
        """Recompute the outputs from the current inputs, parameters and wheel angle."""
        if not self.dirty:
            return
        self.dirty = False
        if self._settings_invalid():
            return  # keep the last valid outputs; the next doStep refuses with the reason
        v = self.values
        u, p = self._inputs_and_parameters()
        if v["quasi_static"]:
            # warm start: from the last solved sinkage (none yet: 0, cold)
            guess = float(v.get("contact_sinkage", 0.0)) if v["warm_start"] else 0.0
            y, status, info = self.quasi_static(u, p, guess)
        else:
            y, status, info, _ = self.dynamic(u, self.angle, self.plastic, p)
        if self._operating_point(None if status == fmu_model.STATUS_OK else
                                 fmu_model.status_message(int(status), info, u)):
            return
        v.update(zip(fmu_model.TERRAIN_OUTPUTS, y, strict=True))
        v["wheel_angle"] = self.angle
        v["plastic_sinkage"] = self.plastic

    def initialize(self) -> None:
        # Logged here, not at instantiation: pythonfmu 0.7 crashes the host (SIGSEGV) when an
        # instance freed right after fmi2Instantiate still has a message queued
        # (fmu_src/README.md, upstream notes).
        from pythonfmu.enums import Fmi2Status
        self.slave.log(f"WheelTerrain: contact model evaluated by {self.evaluator}",
                       Fmi2Status.ok)
        self.initialized = True
        self.dirty = True
        self.refresh()

    def do_step(self, t: float, h: float) -> bool:
        """Check the step's inputs, advance the wheel angle and the plastic sinkage, as
        fmi2_native.c does. Inputs not evaluated since they were set are evaluated once, at
        the step's end (what the master reads next: a set + doStep + get costs one
        evaluation); the terrain's refusals depend on its inputs, not on its states, and a
        refused step is not taken. Inputs already evaluated (a master that reads before it
        steps) were checked then; the outputs at the step's end are computed when first read,
        and a problem found then refuses the next step."""
        if not self.step_allowed(t, h):
            return False
        if self.dirty and not self._settings_invalid():
            start = self.angle, self.plastic
            self._advance(h)
            self.refresh()
            if self.refuse_if_invalid():
                return True
            self.angle, self.plastic = start
            return False
        self.refresh()
        if not self.refuse_if_invalid():
            return False
        self._advance(h)
        self.dirty = True
        return True


_PARAMETERS = {**BY_NAME,
               **{p.name: p for p in (*rig.RIG_TABLE, *ROVER_TABLE, *GROUND_TABLE)}}
OPERATING_POINT = "operating point"  # the key of the error the model's status reports


class StateCore(_Core):
    """A state-space FMU (:class:`wheelterrain.fmu.functions.StateModel`): its state advanced by
    the model's step with the inputs held, its outputs from the state."""

    model_name = ""

    def __init__(self, slave) -> None:
        follow_resources(getattr(slave, "resources", None))
        self.model = fmu_model.STATE_MODELS[self.model_name]
        super().__init__(slave, VARIABLES[self.model_name]())
        self.state = tuple(self.model.initial(self.params()))
        self.memory = (0.0,) * self.model.memory

    def params(self) -> dict[str, float]:
        return {name: float(self.values[name]) for name in self.model.parameters}

    def internal_state(self) -> dict:
        return {"state": list(self.state), "memory": list(self.memory)}

    def set_internal_state(self, state: dict) -> None:
        self.state = tuple(float(x) for x in state["state"])
        self.memory = tuple(float(x) for x in state["memory"])

    def initialize(self) -> None:
        self.initialized = True
        if not self.errors:
            self.state = tuple(self.model.initial(self.params()))
        self.dirty = True
        self.refresh()

    def refresh(self) -> None:
        if not self.dirty:
            return
        self.dirty = False
        if self._settings_invalid() or self._operating_point(self.model.problem(self.state)):
            return
        y = self.model.output_values(self.state, self.inputs(), self.params(), self.memory)
        self.values.update(zip(self.model.outputs, y, strict=True))

    def inputs(self) -> tuple[float, ...]:
        return tuple(float(self.values[name]) for name in self.model.inputs)

    def do_step(self, t: float, h: float) -> bool:
        if not self.step_allowed(t, h):
            return False
        if not self.refuse_if_invalid():
            return False
        state, memory = self.model.step(self.state, self.inputs(), self.params(), h)
        self.state, self.memory = tuple(state), tuple(memory)
        self.dirty = True
        self.refresh()
        return True


class RigCore(StateCore):
    """SingleWheelRig: carriage, wheel drive, vertical motion (rig.step)."""

    model_name = "SingleWheelRig"


class RoverCore(StateCore):
    """RoverChassis: the rover's chassis on four driven wheels (rover.step)."""

    model_name = "RoverChassis"


class GroundCore(StateCore):
    """Terrain: a terrain map's query point, the soil at its position (model.ground)."""

    model_name = "Terrain"
