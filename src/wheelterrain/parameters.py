"""The one table of wheel, grouser, soil, ripple, model and rig parameters.

Every other face of the project (the CasADi functions, the FMU variables, the CLI's ``--set`` keys,
the JSON printed by ``wheelterrain params``, calibration's plausible ranges) is generated from
:data:`ROWS`: :data:`TABLE`, the terrain model's parameters, then :data:`RIG_TABLE`, the rig's.
A parameter has a structured name (``soil.phi``), an SI unit, a default, a closed valid range
``[min, max]``, a description, the source of its default and the FMU that carries it.
Presets (see :mod:`wheelterrain.presets`) override the defaults with documented values.

Ranges are *validity* ranges: the model is defined, finite and tested at every corner of the box
they span (see ``tests/test_robustness.py``). Values outside are rejected with an error that names
the parameter and its range; nothing is clamped.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from wheelterrain.errors import ParameterError

DEG = math.pi / 180.0
TERRAIN_FMU, RIG_FMU, ROVER_FMU, GROUND_FMU = ("WheelTerrain", "SingleWheelRig", "RoverChassis",
                                              "Terrain")


@dataclass(frozen=True)
class Parameter:
    """One row of the parameter table.

    ``kind`` is ``"real"``, ``"integer"`` (a count) or ``"enum"`` (a switch whose allowed values are
    the integers of ``choices``). ``quantity`` names the Modelica.Units.SI type where one exists.
    """

    name: str
    unit: str
    default: float
    min: float
    max: float
    description: str
    source: str
    kind: str = "real"
    quantity: str | None = None
    display_unit: str | None = None
    choices: Mapping[int, str] | None = None
    plausible: tuple[float, float, str] | None = None
    """(min, max, source): the physically plausible range calibration may use, narrower than
    the validity range [min, max]; None for parameters that are not calibrated."""
    fmu: str = TERRAIN_FMU
    """The FMU that carries the row as a parameter: WheelTerrain (the terrain model's parameter
    vector, :data:`TABLE`) or SingleWheelRig (the rig's, :data:`RIG_TABLE`)."""

    def check(self, value: float) -> float:
        """``value`` as float if valid for this parameter, else raise ParameterError."""
        try:
            number = float(value)
        except (TypeError, ValueError):
            problem = f"is not a number; {self.valid_range()}"
            raise ParameterError(self.name, value, problem) from None
        if not math.isfinite(number):
            raise ParameterError(self.name, value, f"must be finite; {self.valid_range()}")
        if not (self.min <= number <= self.max):
            raise ParameterError(self.name, value, f"is out of range; {self.valid_range()}")
        if self.kind in ("integer", "enum") and number != round(number):
            raise ParameterError(self.name, value, f"must be a whole number; {self.valid_range()}")
        return number

    def valid_range(self) -> str:
        """Human-readable valid range, in the unit (and display unit for angles)."""
        if self.kind == "enum" and self.choices:
            opts = ", ".join(f"{k} = {v}" for k, v in self.choices.items())
            return f"valid values: {opts}"
        text = f"valid range [{self.min:g}, {self.max:g}] {self.unit}"
        if self.unit == "rad":
            text += f" ([{self.min / DEG:g}, {self.max / DEG:g}] deg)"
        return text

    def as_dict(self, value: float | None = None) -> dict:
        """JSON-ready description; ``value`` is the preset's value (default if None)."""
        row = {
            "name": self.name,
            "unit": self.unit,
            "value": self.default if value is None else value,
            "default": self.default,
            "min": self.min,
            "max": self.max,
            "kind": self.kind,
            "description": self.description,
            "source": self.source,
            "fmu": self.fmu,
        }
        if self.quantity:
            row["quantity"] = self.quantity
        if self.display_unit:
            row["display_unit"] = self.display_unit
        if self.choices:
            row["choices"] = {str(k): v for k, v in self.choices.items()}
        if self.plausible:
            row["plausible"] = {"min": self.plausible[0], "max": self.plausible[1],
                                "source": self.plausible[2]}
        return row


_P = Parameter
_PAPER = "Abubakar et al., Rashid rover wheel-terrain study"
_TABLE2 = f"{_PAPER}, Table II (tuned)"
_LUNAR = ("Lunar regolith and its simulants (Carrier, Olhoeft & Mendell, Lunar Sourcebook "
          "1991, ch. 9)")

TABLE: tuple[Parameter, ...] = (
    # --- wheel -------------------------------------------------------------------------------
    _P("wheel.radius", "m", 0.05, 0.01, 1.0,
       "Rim radius R of the rigid wheel (grousers excluded).",
       f"{_PAPER}: diameter 0.1 m", quantity="Length"),
    _P("wheel.width", "m", 0.075, 0.005, 1.0,
       "Wheel width b; also the plate width in the Reece pressure-sinkage law.",
       f"{_PAPER} prints 0.0075 m; read as 0.075 m because at 0.0075 m even a fully buried wheel "
       "carries only ~15 N of the 62 N measured", quantity="Length"),
    # --- grousers ----------------------------------------------------------------------------
    _P("grouser.count", "1", 12, 0, 100,
       "Number of grousers n_g around the rim; sets the ripple phase psi = n_g * wheel angle.",
       f"{_PAPER}: 12", kind="integer"),
    _P("grouser.height", "m", 0.01, 0.0, 0.1,
       "Grouser height h_g above the rim (the paper's h_b).",
       f"{_PAPER}: grouser height 0.01 m; h_b = 0.01 m in Tables I/II read as the same length",
       quantity="Length"),
    # --- soil --------------------------------------------------------------------------------
    _P("soil.cohesion", "Pa", 0.0, 0.0, 20000.0,
       "Cohesion c (Mohr-Coulomb shear strength and Reece pressure-sinkage).",
       f"{_TABLE2}: 0 kPa", quantity="Pressure",
       plausible=(0.0, 3000.0, f"{_LUNAR}: 0.1-3 kPa")),
    _P("soil.phi", "rad", 23 * DEG, 0.0, 60 * DEG,
       "Internal friction angle phi (Mohr-Coulomb).",
       f"{_TABLE2}: 23 deg (Table I: 28 deg)", quantity="Angle", display_unit="deg",
       plausible=(25 * DEG, 50 * DEG, f"{_LUNAR}: friction angle 30-50 deg; Table I 28 deg")),
    _P("soil.k_c", "1", 0.63, 0.0, 2000.0,
       "Reece cohesive modulus k_c' (dimensionless); multiplies c, so it has no effect when c = 0.",
       f"{_TABLE2}: 0.63 (Table I: 0)",
       plausible=(0.0, 100.0, "Reece k_c' (Wong: dry sand 0.99, sandy loam 2-4)")),
    _P("soil.k_phi", "1", 80.0, 10.0, 5000.0,
       "Reece frictional modulus k_phi' (dimensionless).",
       f"{_TABLE2}: 80; range after Wong, Theory of Ground Vehicles (Reece parameters of "
       "measured soils span tens to a few thousand)",
       plausible=(10.0, 2000.0, "Reece k_phi' of sands and simulants (Wong, Theory of Ground "
                  "Vehicles: dry sand 1528; Table I/II 80)")),
    _P("soil.n0", "1", 1.1, 0.3, 2.0,
       "Sinkage exponent at zero slip, n0 in n = n0 + n1*max(sigma, 0); the exponent in "
       "skid (held there: no skid-sinkage law in the sources).",
       f"{_TABLE2}: n = 1.1 (Table I: 1)",
       plausible=(0.5, 1.5, "Reece sinkage exponent of sands, 0.5-1.3 (Wong); Table II 1.1")),
    _P("soil.n1", "1", 0.0, 0.0, 2.0,
       "Slip-sinkage coefficient n1 in n = n0 + n1*max(sigma, 0) (sigma the model's slip, the "
       "traction slip when driving). Driving only: Ding et al. fitted it on driven wheels. "
       "0 = classical model.",
       "Ding et al. 2011, J. Terramechanics 48 (slip-sinkage exponent); presets read the paper's "
       "eta = 1.15 as n1 (it reproduces the measured sinkage trend)",
       plausible=(0.0, 2.0, "Slip-sinkage coefficient (Ding et al. 2011 report n1 ~ 0.3-1 for "
                  "lunar simulant; paper's eta 1.15)")),
    _P("soil.gamma", "N/m3", 15620.0, 5000.0, 30000.0,
       "Soil weight density gamma (Reece pressure-sinkage law).",
       f"{_TABLE2}: 15620 N/m3 (Table I: 13734)"),
    _P("soil.shear_modulus", "m", 0.036, 5e-4, 0.1,
       "Shear deformation modulus K (Janosi), and the peak-shear displacement K_w of Wong's hump "
       "form.",
       f"{_TABLE2}: K = 0.036 m; equals Ishigami et al. 2007's K_x at zero slip angle. "
       "Range after Wong, Theory of Ground Vehicles (measured K from below 1 mm to a few cm)",
       quantity="Length",
       plausible=(0.002, 0.04, "Janosi K of sands, 2-40 mm (Wong; Table II 36 mm)")),
    _P("soil.residual_ratio", "1", 0.6, 0.1, 1.0,
       "Residual-to-peak shear ratio K_r of Wong's hump shear form (unused with Janosi shear).",
       "Wong, Theory of Ground Vehicles (hump-type shear, K_r typically 0.3-1); the paper gives "
       "no value, 0.6 is an assumption"),
    _P("soil.gamma_variation", "N/m3", 1562.0, 0.0, 10000.0,
       "Weight-density variation d_gamma driving the density part of the grouser ripple.",
       f"{_TABLE2}: d_gamma = 0.1*gamma"),
    _P("soil.damping", "N.s/m", 800.0, 0.0, 1e5,
       "Vertical contact damping C_f: adds C_f * (sinkage rate) to the normal force while in "
       "contact. The quasi-static solve (zero rate) does not see it.",
       f"{_TABLE2}: C_f = 800 N.s/m, read as the vertical damper of the wheel's contact",
       quantity="TranslationalDampingConstant"),
    _P("soil.rut_depth", "m", 0.0, 0.0, 0.5,
       "Depth below the original surface of the rut earlier passes left here: the free "
       "surface of soil pressed plastically before (its yield depth lies the elastic "
       "rebound sigma/K_u below it; see soil.unloading_stiffness). 0 = virgin soil. A wheel "
       "meets it with model.soil_memory = 1; a terrain with memory supplies it per position.",
       "Wong, Theory of Ground Vehicles, ch. 2 (response to repetitive loading); the multi-pass "
       "effect of a rut: Holm 1969; Senatore & Iagnemma 2011", quantity="Length",
       display_unit="mm"),
    _P("soil.rut_pressure", "Pa", 0.0, 0.0, 1.0e7,
       "Pressure the rut (soil.rut_depth) carried at its deepest point when it was made: "
       "the wheel that made it pressed the soil there to this yield pressure. A wheel "
       "meeting the rut reloads it elastically up to it (over the rebound "
       "soil.rut_pressure/K_u), then along its own pressure-sinkage law from the depth at "
       "which that law carries it. 0 = not known: read from the rut's depth with the "
       "meeting wheel's own law (exact where it runs at the maker's slip, to first order in "
       "the rebound). A terrain with memory records it with each rut (rut_pressure_left).",
       "Wong, Theory of Ground Vehicles, ch. 2 (repetitive loading: the soil reloads "
       "elastically up to the largest pressure it carried); Krenn & Hirzinger 2009, SCM (each "
       "soil node keeps its yield pressure sigma_yield)", quantity="Pressure",
       display_unit="kPa"),
    _P("soil.unloading_stiffness", "Pa/m", 4.0e7, 1.0e5, 1.0e10,
       "Stiffness K_u of the soil's unloading and reloading line (pressure per depth): below "
       "the largest pressure the soil has carried it answers elastically, p = K_u*(z - z_p); "
       "beyond it, along the pressure-sinkage law. Its rebound sigma/K_u is the part of a "
       "sinkage that springs back.",
       "Wong, Theory of Ground Vehicles, ch. 2 (repetitive loading: a stiff, nearly linear "
       "unloading-reloading line); Krenn & Hirzinger 2009, SCM (elastic stiffness, larger "
       "than k_phi; Project Chrono's SCM demos use 4e7-4e8 Pa/m)",
       plausible=(4.0e6, 4.0e8, "SCM demos 4e7-4e8 Pa/m; a decade softer for loose sand")),
    # --- grouser ripple (Irani et al. 2011) --------------------------------------------------
    _P("ripple.k_g", "1", 0.0, 0.0, 1.0,
       "Stress coefficient k_g' of the ripple amplitude A = k_g'*mean_pressure + "
       "k_0'*contact_length*d_gamma. 0 with k_0' = 0 switches the ripple off.",
       f"Irani, Bauer & Warkentin 2011, J. Terramechanics 48:307-318; {_TABLE2}: 0.07"),
    _P("ripple.k_0", "1", 0.0, 0.0, 1.0,
       "Density coefficient k_0' (the text's k_a') of the ripple amplitude.",
       f"Irani et al. 2011; {_TABLE2}: 0.035"),
    _P("ripple.phase", "rad", 0.0, -2 * math.pi, 2 * math.pi,
       "Phase Phi of the ripple sin(n_g*wheel_angle + Phi).",
       "Irani et al. 2011; the paper gives no value", quantity="Angle", display_unit="deg"),
    # --- model form --------------------------------------------------------------------------
    _P("model.a0", "1", 0.40, 0.32, 0.5,
       "Max-stress angle coefficient a0 in theta_m = (a0 + a1*sigma)*theta_f (sigma the model's "
       "slip). Its lower bound is model.a1's upper one: theta_m >= 0 down to the locked wheel "
       "(sigma = -1).",
       "Ishigami et al. 2007, J. Field Robotics 24(3): 0.40 for lunar simulant (Wong-Reece sand: "
       "0.43)",
       plausible=(0.32, 0.45, "Wong & Reece 1967; Ishigami et al. 2007: a0 0.3-0.45")),
    _P("model.a1", "1", 0.15, 0.0, 0.32,
       "Max-stress angle coefficient a1 in theta_m = (a0 + a1*sigma)*theta_f. Bounded by "
       "model.a0's lower bound, so that theta_m >= 0 down to the locked wheel.",
       "Ishigami et al. 2007: 0.15 for lunar simulant (Wong-Reece sand: 0.32)",
       plausible=(0.0, 0.32, "Wong & Reece 1967 (sand 0.32); Ishigami et al. 2007 (lunar "
                  "simulant 0.15)")),
    _P("model.exit_ratio", "1", 0.0, 0.0, 1.0,
       "Exit-angle ratio lambda: theta_r = -arccos(1 - lambda*z/R_c). 0 = Wong-Reece "
       "(theta_r = 0); "
       "Ishigami 2007 uses about 0.9.",
       "Wong & Reece 1967; Ishigami et al. 2007",
       plausible=(0.0, 0.9, "Ishigami et al. 2007: lambda ~ 0.9; Wong-Reece 0")),
    _P("model.shear_model", "1", 0, 0, 1,
       "Shear-stress law: 0 = Janosi 1 - exp(-j/K); 1 = Wong's hump form (paper eq. 3).",
       "Janosi & Hanamoto 1961; Wong, Theory of Ground Vehicles", kind="enum",
       choices=MappingProxyType({0: "janosi", 1: "wong-hump"})),
    _P("model.contact_radius_factor", "1", 0.0, 0.0, 1.0,
       "Contact radius R_c = R + factor*h_g used for the geometry and the normal stress "
       "(0 = rim, 1 = grouser tips). Sinkage is measured to this circle.",
       "grouser-tip effective radius (Wong, Theory of Ground Vehicles, lugged wheels)",
       plausible=(0.0, 1.0, "Definition: rim (0) to grouser tips (1)")),
    _P("model.shear_radius_factor", "1", 0.0, 0.0, 1.0,
       "Shearing radius R_s = R + factor*h_g used in the shear displacement, the shear terms and "
       "the torque (lambda_s of Ding et al.).",
       "Ding et al. 2011, J. Terramechanics 48",
       plausible=(0.0, 1.0, "Definition: rim (0) to grouser tips (1)")),
    _P("model.slip_radius_factor", "1", 0.0, 0.0, 1.0,
       "Radius R_ref = R + factor*h_g to which the slip input is referenced: carriage speed "
       "V = (1 - i)*omega*R_ref driving, omega*R_ref/(1 + s) braking. 0 = rim radius, as the rig "
       "defines slip from omega_r*R.",
       f"{_PAPER}, eq. 4 (slip from omega_r*R)",
       plausible=(0.0, 1.0, "Definition: rim (0) to grouser tips (1)")),
    _P("model.grouser_thrust", "1", 0, 0, 1,
       "Grouser thrust by passive earth pressure: 0 = off; 1 = the Rankine passive force on the "
       "buried part of each grouser face (depth below the surface as surcharge), mobilised "
       "like the shear stress, g(j), and spread over the grouser spacing 2*pi/n_g.",
       "Bekker 1960, Off-the-road locomotion (grouser thrust); Rankine passive earth pressure "
       "(Wong, Theory of Ground Vehicles, ch. 2)", kind="enum",
       choices=MappingProxyType({0: "off", 1: "passive-earth-pressure"})),
    _P("model.shear_kinematics", "1", 0, 0, 1,
       "Whose slip the Janosi displacement j counts: 0 = the wheel-surface element's since it "
       "entered the soil (Wong-Reece); 1 = the soil element's since the wheel reached it, as the "
       "Soil Contact Model accumulates it per soil node (j linear in the paper's slip s).",
       "Wong & Reece 1967 (0); Krenn & Hirzinger 2009, SCM, as in Project Chrono's SCMTerrain "
       "(1)", kind="enum", choices=MappingProxyType({0: "wheel-element", 1: "soil-element"})),
    _P("model.contact_form", "1", 0, 0, 1,
       "How the soil's stresses act on the wheel: 0 = arc, the Wong-Reece stress distribution "
       "integrated over the contact arc; 1 = patch, the Reece pressure p(z) acting uniformly on "
       "the flat contact patch (width b, chord between the entry and exit angles), thrust by "
       "Janosi (or hump) shear over the patch length and Bekker's compaction resistance.",
       "Wong & Reece 1967 (0); Bekker 1956/1960 and Wong, Theory of Ground Vehicles, ch. 2 and "
       "4 (1), the soft-soil reading of Abubakar et al.'s eq. 1", kind="enum",
       choices=MappingProxyType({0: "arc", 1: "patch"})),
    _P("model.soil_memory", "1", 1, 0, 1,
       "Soil with memory: 1 = elastic-plastic: a wheel in a rut (soil.rut_depth, or the "
       "rut_met a terrain with memory gives) meets soil that answers elastically up to the "
       "pressure it has carried and plastically beyond, its contact beginning at the rut's "
       "surface; a wheel lifted from where it yielded (plastic_sinkage) unloads along the "
       "same elastic line; it leaves a rut (rut_left). 0 = the elastic soil: ruts ignored, "
       "none left, the same numbers as before the soil had memory, exactly.",
       "Wong, Theory of Ground Vehicles, ch. 2 (repetitive loading); Krenn & Hirzinger 2009 "
       "(SCM's elastic-plastic soil node)", kind="enum",
       choices=MappingProxyType({0: "off", 1: "elastic-plastic"})),
    _P("model.rut_shear", "1", 1.0, 0.0, 1.0,
       "Shear a rut remembers: the share of the shear displacement the wheel that made a rut "
       "left at its exit that a wheel in the rut (model.soil_memory = 1, soil.rut_depth > 0) "
       "inherits and counts its Janosi displacement on from, taking the rut's maker to have run "
       "at this wheel's slip with its radius and soil (its exit displacement at the rut's yield "
       "depth, buried to the axle at most). 1 = all of it, as the Soil Contact Model keeps each "
       "soil node's accumulated shear displacement from contact to contact (the default: the "
       "multi-pass direction of that node law, tests/test_multipass_scm.py); 0 = every "
       "wheel's displacement starts at 0 at its entry, as on virgin soil. Unused where the "
       "wheel meets virgin soil.",
       "Krenn & Hirzinger 2009 and Chrono's SCMTerrain (the node's accumulated shear "
       "displacement, kept across contacts); Wong, Theory of Ground Vehicles, ch. 2 (repetitive "
       "shear loading: reloaded soil takes up its shear stress again within a short "
       "displacement). Multi-pass traction rising in a rut: Holm 1969",
       plausible=(0.0, 1.0, "unmeasured: 0 (reloaded soil shears afresh) to 1 (SCM's node "
                  "keeps all of it); the rover's limit_band spans both ends")),
    _P("model.imprint_relaxation", "1", 1, 0, 1,
       "What the imprint under a rolling wheel lifted from where it yielded relaxes toward, "
       "at the rate |V|/l it rolls onto soil it has not pressed (model.soil_memory = 1): "
       "0 = toward the wheel (the imprint follows the wheel up only by its elastic rebound per "
       "contact length: a wheel whose load falls closes 12 % of the step in five contact "
       "lengths); 1 = toward the sinkage z_t at which the soil ahead carries the force the "
       "wheel carries now (Bekker's rigid wheel, F ~ (z - s)**((2n+1)/2) from the surface s "
       "it meets: a load step settles within a few contact lengths, 62 % of it in one). 1, "
       "the physical law, is the default since each rut keeps the pressure it carried "
       "(soil.rut_pressure; with the rut read from its depth it closed a loop through the "
       "ruts on the Moon's climb from 20.5 deg: docs/model.md, Known limits).",
       "Wong, Theory of Ground Vehicles, 4th ed., sec. 2.4.2 (rigid wheel: W from the "
       "pressure-sinkage law, z**((2n+1)/2)); Krenn & Hirzinger 2009 (SCM: a node meeting the "
       "wheel for the first time yields along the pressure-sinkage law)", kind="enum",
       choices=MappingProxyType({0: "toward the wheel", 1: "toward the soil ahead"})),
    # --- lateral mechanics (a wheel at a slip angle: docs/model.md, "Lateral mechanics") -------
    _P("model.lateral_shear_ratio", "1", 1.0, 0.05, 5.0,
       "Lateral shear deformation modulus K_y as a share of the soil's K: the lateral shear "
       "stress of a wheel at a slip angle is (c + sigma*tan(phi))*g(j_y) with the modulus "
       "K_y = ratio*K. 1 = isotropic (one K for any direction of the displacement).",
       "Ishigami, Miwa, Nagatani & Yoshida 2007, J. Field Robotics 24(3) (K_x and K_y fitted "
       "apart on a lunar simulant, K_y the smaller); isotropic: the Soil Contact Model's one "
       "Janosi K for a node's tangential displacement (Krenn & Hirzinger 2009), Jia et al. "
       "2011", plausible=(0.3, 1.0, "assumption: from isotropic (1) down to a lateral modulus "
                          "about a third of the longitudinal, the anisotropy Ishigami et al. "
                          "2007 report (their fitted values were not at hand)")),
    _P("model.side_bulldozing", "1", 1.0, 0.0, 1.0,
       "Share of the bulldozing resistance of the wheel's side face that a wheel at a slip "
       "angle meets (the soil wedge its side pushes: Hegedus's bulldozing over the buried "
       "side face, mobilised like the lateral shear). 0 = the lateral shear alone.",
       "Ishigami, Miwa, Nagatani & Yoshida 2007 (side-face bulldozing after Hegedus 1960, "
       "soil destructive angle pi/4 - phi/2)"),
    # --- cross-wheel mechanisms (validation/DATA.md; chosen by leave-one-dataset-out) ----------
    _P("model.shear_length_ratio", "1", 0.0, 0.0, 2.0,
       "Growth of the shear deformation modulus with the length of the shearing surface: "
       "K_eff = K + ratio*l, l the contact length. 0 = Janosi's K for every contact; > 0 makes "
       "the mobilisation x*l/K_eff tend to x/ratio on long contacts instead of to full strength.",
       "Wiendieck 1968 (US Army WES Misc. Paper M-68-6): the shear stress-displacement curve "
       "depends on the size of the sheared surface; the linear form is this project's",
       plausible=(0.0, 1.0, "K_eff between Janosi's K and K + contact length")),
    _P("model.interface_ratio", "1", 1.0, 0.1, 1.0,
       "Rim-soil interface friction as a share of the soil's: delta = ratio*phi and adhesion "
       "c_a = ratio*c on the rim between grousers (see model.grouser_shear_height). 1 = the "
       "classical model (the rim shears the soil at its full strength).",
       "Potyondy 1961, Geotechnique 11(4):339-353 (skin friction of sands on steel, "
       "delta/phi ~0.5-0.9); Higa, Nagaoka & Yoshida 2019 (grousered wheels: traction acts at "
       "the grousers)",
       plausible=(0.5, 1.0, "Potyondy 1961: delta/phi of sand on steel, wood, concrete")),
    _P("model.grouser_shear_height", "m", 0.0, 0.0, 0.1,
       "Grouser height at which half the shearing surface is soil on soil (at the grouser "
       "tips) and half rim on soil: the soil-on-soil share is h_g/(h_g + this); 0 = any "
       "grouser makes it all soil on soil, a smooth rim none. Unused when "
       "model.interface_ratio = 1.",
       "Higa, Nagaoka & Yoshida 2019 (nearly all traction of a grousered wheel acts at the "
       "grousers); the saturating form is this project's", quantity="Length",
       plausible=(0.0, 0.02, "0 (any grouser engages) to 20 mm")),
    _P("model.bulldozing", "1", 0.0, 0.0, 1.0,
       "Bulldozing resistance as a share of the Rankine passive force on the wheel's front "
       "over its sinkage: R_b = share*b*(gamma*z**2*K_p/2 + 2*c*z*sqrt(K_p)), "
       "K_p = tan(pi/4 + phi/2)**2, subtracted from the drawbar pull. It grows with the "
       "sinkage, so with slip where the sinkage does. 0 = off (the classical model).",
       "Bekker 1956/1960 (bulldozing resistance of the soil wedge ahead of a sinking wheel); "
       "Wong, Theory of Ground Vehicles, ch. 4 (its passive-pressure form); the share is this "
       "project's", plausible=(0.0, 1.0, "0 (no wedge) to the full Rankine passive force. "
                                  "Bekker's bulldozing coefficients give 12-31 times more at "
                                  "phi 25-40 deg; so bounded, the cross-wheel fits reach "
                                  "1.2-2.1 and the held-out pull worsens (6.78 -> 8.56 N)")),
    _P("model.diameter_exponent", "1", 0.0, -1.0, 1.0,
       "Diameter dependence of the pressure-sinkage modulus: multiplied by "
       "(2R/0.5 m)**exponent. 0 = the flat-plate (Bekker/Reece) law.",
       "Meirion-Griffith & Spenko 2011, J. Terramechanics 48(2):149-155 (the flat-plate "
       "assumption fails below ~50 cm diameter; pressure-sinkage with a power of the diameter)",
       plausible=(0.0, 1.0, "Meirion-Griffith & Spenko 2011: flat-plate models under-predict "
                  "the sinkage of wheels below ~50 cm (a softer soil under a smaller wheel), so "
                  "the exponent is >= 0; the upper bound 1 is not from the source")),
)

# --- the single-wheel rig (SingleWheelRig.fmu) ------------------------------------------------
# Same columns; ``fmu`` says which FMU carries the row. The CasADi terrain model's parameter
# vector is TABLE (the terrain rows); the rig's is RIG_TABLE.
STANDARD_GRAVITY = 9.80665  # m/s2: the rig's load as a mass (rig.mass = load/g)
NO_RIPPLE = {"ripple.k_g": 0.0, "ripple.k_0": 0.0}
"""The grouser ripple off: the contact's grouser-period mean (the data's means, the steady
motion a rover limit is predicted from)."""
SLIP_ANGLE_LIMIT = math.radians(80.0)
"""rad: the largest |slip angle| the lateral contact takes, in every face (the API, the FMU's
input, a sweep's axis, a test file's column): tan(beta), the sideways travel per metre
forward, is 5.7 there; a wheel moving sideways, 90 deg, has no heading to slip along."""
TURN_SLIP_LIMIT = 10.0
"""rad/m: the largest |turn slip| (a wheel's yaw rate over its forward speed, the curvature of
its path) the lateral contact takes, in every face: a path no tighter than a 0.1 m radius. The
contact's shear is the displacement accumulated since the soil entered it (:class:`
wheelterrain.model.contact._Sideways`), right while the yaw's share of it is not far past the
shear modulus; the Rashid rover's point turn asks about 2/track (5 rad/m for a 0.4 m track),
and a wheel yawing on the spot (infinite turn slip) is outside the model."""
GRAVITY = {"earth": 9.81, "moon": 1.62}
"""m/s2: the gravities a rover runs in (``wheelterrain rover --gravity``; the rover.gravity
row's default is the Earth's) and the Earth's of the shipped wheel tests' soil weights."""


def _R(*args, **kwargs) -> Parameter:
    return Parameter(*args, fmu=RIG_FMU, **kwargs)


_RIG = "The paper's single-wheel rig (Abubakar et al., Rashid rover wheel-terrain study)"
_RIG_ROWS: tuple[Parameter, ...] = (
    _R("rig.load", "N", 62.0, 0.0, 1.0e5,
              "Vertical load the rig applies to the wheel axle (the paper's normal force).",
              f"{_RIG}: ~62 N measured in every case", quantity="Force"),
    _R("rig.mass", "kg", 62.0 / STANDARD_GRAVITY, 0.01, 1.0e4,
              "Mass that moves vertically with the wheel (wheel, axle, dead weight).",
              "Dead-weight reading: load / standard gravity; the paper does not state it",
              quantity="Mass"),
    _R("rig.rim_speed", "m/s", 0.03, 1.0e-4, 10.0,
              "Commanded wheel rim speed omega_ref*R_ref.",
              f"{_RIG}: 3 cm/s in C1-C4", quantity="Velocity"),
    _R("rig.slip_paper", "1", 0.0, 0.0, 10.0,
              "Commanded slip in the paper's definition s = (omega*R - V)/V; sets the carriage "
              "speed V = rim_speed/(1 + s). Traction slip i = s/(1 + s).",
              f"{_RIG}: 0, 0.25, 0.5, 0.75 in C1-C4"),
    _R("rig.slip_radius", "m", 0.05, 0.01, 1.0,
              "Radius R_ref the rig's slip is referenced to; must equal the terrain model's "
              "wheel.radius + model.slip_radius_factor*grouser.height.",
              f"{_RIG}: rim radius 0.05 m", quantity="Length"),
    _R("rig.wheel_inertia", "kg.m2", 0.01, 1.0e-6, 100.0,
              "Rotational inertia of wheel and motor about the axle.",
              "Estimate: 1 kg wheel of 5 cm radius plus geared motor; the paper does not state it",
              quantity="MomentOfInertia"),
    _R("rig.speed_bandwidth", "rad/s", 200.0, 0.1, 1.0e4,
              "Closed-loop bandwidth of the wheel speed controller (both poles at -bandwidth).",
              "Design choice for a stiff geared servo. It must be: with the slip-dependent "
              "exponent the soil softens as slip grows, so the soil torque falls with wheel "
              "speed (dT/domega ~ -0.4 N.m.s at C2); a 20 rad/s loop (Kp = 0.4 N.m.s) then "
              "limit-cycles, as measured", quantity="AngularVelocity"),
    _R("rig.drive", "1", 0, 0, 2,
              "Wheel drive: 0 = speed loop to rig.rim_speed/rig.slip_radius (the paper's rig); "
              "1 = speed loop to the input wheel_speed_command; 2 = the input "
              "motor_torque_command applied directly (no speed loop).",
              "Design: 0 reproduces the paper; 1 and 2 are for external controllers "
              "(wheelterrain.control.mpc)", kind="enum",
              choices=MappingProxyType({0: "paper-speed-loop", 1: "speed-command",
                                        2: "torque-command"})),
    _R("rig.carriage", "1", 0, 0, 1,
              "Carriage: 0 = kinematic at rim_speed/(1 + slip_paper) (the paper's rig); 1 = free, "
              "its speed a state driven by the drawbar pull against rig.slope and "
              "rig.towing_force, with mass rig.mass.",
              "Design: 1 is a rover wheel carrying its share of the vehicle", kind="enum",
              choices=MappingProxyType({0: "kinematic", 1: "free"})),
    _R("rig.towing_force", "N", 0.0, -1.0e4, 1.0e4,
              "Force resisting the free carriage's forward motion (a towed load, the rest of the "
              "rover); negative pushes.", "Scenario input; 0 on the level with nothing in tow",
              quantity="Force"),
    _R("rig.slope", "rad", 0.0, -45 * DEG, 45 * DEG,
              "Slope the free carriage climbs: adds rig.mass*g*sin(slope) against its motion.",
              "Scenario input; lunar rovers are specified for ~15-25 deg slopes",
              quantity="Angle", display_unit="deg"),
)
RIG_TABLE = _RIG_ROWS

# --- the rover's chassis (RoverChassis.fmu) ---------------------------------------------------


def _V(*args, **kwargs) -> Parameter:
    return Parameter(*args, fmu=ROVER_FMU, **kwargs)


_ROVER = "Rashid rover (MBRSC): ~10 kg with payload, ~50 cm x 50 cm footprint, four wheels"
_ASSUMED = "Assumption (the rover's published figures do not give it); documented in README"
ROVER_TABLE: tuple[Parameter, ...] = (
    _V("rover.mass", "kg", 10.0, 0.1, 1.0e4,
       "Mass of the whole rover (chassis, payload and wheels), carried by four wheels.",
       f"{_ROVER}: about 10 kg", quantity="Mass"),
    _V("rover.pitch_inertia", "kg.m2", 0.24, 1.0e-4, 1.0e4,
       "Moment of inertia of the rover about the pitch axis through its centre of mass.",
       f"{_ASSUMED}: a 10 kg box 0.5 m long and 0.2 m high, m*(L**2 + H**2)/12",
       quantity="MomentOfInertia"),
    _V("rover.wheelbase", "m", 0.40, 0.05, 10.0,
       "Distance between the front and the rear axle.",
       f"{_ASSUMED}: the axles 5 cm inside the 50 cm footprint", quantity="Length"),
    _V("rover.cg_forward", "m", 0.0, -1.0, 1.0,
       "Centre of mass ahead of the middle of the wheelbase (negative: behind it). Must stay "
       "within half the wheelbase.",
       f"{_ASSUMED}: centred", quantity="Length"),
    _V("rover.cg_height", "m", 0.10, 0.0, 2.0,
       "Height of the centre of mass above the axles: with the slope it moves load from the "
       "front to the rear axle (load transfer).", f"{_ASSUMED}: 10 cm", quantity="Length"),
    _V("rover.gravity", "m/s2", GRAVITY["earth"], 0.1, 30.0,
       "Gravitational acceleration: Earth test bed 9.81 (standard 9.80665), Moon 1.62.",
       "Earth: standard gravity; Moon: 1.62 m/s2", quantity="Acceleration"),
    _V("rover.rim_speed", "m/s", 0.03, 1.0e-4, 10.0,
       "Commanded wheel rim speed omega_ref*R_ref of all four speed loops (rover.drive = 0).",
       "The rig's 3 cm/s (the Rashid rover's top speed is about 10 cm/s)",
       quantity="Velocity"),
    _V("rover.slip_radius", "m", 0.05, 0.01, 1.0,
       "Radius R_ref the wheels' slip is referenced to; must equal the terrain model's "
       "wheel.radius + model.slip_radius_factor*grouser.height.",
       f"{_PAPER}: rim radius 0.05 m", quantity="Length"),
    _V("rover.wheel_inertia", "kg.m2", 0.01, 1.0e-6, 100.0,
       "Rotational inertia of one wheel and its motor about the axle.",
       "As the rig (rig.wheel_inertia)", quantity="MomentOfInertia"),
    _V("rover.speed_bandwidth", "rad/s", 200.0, 0.1, 1.0e4,
       "Closed-loop bandwidth of each wheel's speed loop (both poles at -bandwidth).",
       "As the rig (rig.speed_bandwidth)", quantity="AngularVelocity"),
    _V("rover.drive", "1", 0, 0, 2,
       "Wheel drives: 0 = four speed loops to rover.rim_speed/rover.slip_radius; 1 = speed "
       "loops to each wheel's input wheel_speed_command; 2 = each wheel's input "
       "motor_torque_command applied directly.",
       "Design: as the rig's rig.drive", kind="enum",
       choices=MappingProxyType({0: "common-speed", 1: "speed-command",
                                 2: "torque-command"})),
    _V("rover.ramp_time", "s", 0.0, 0.0, 1.0e6,
       "Input profile (so that an SSP carries a scenario whole): the time at which the slope's "
       "rate changes from rover.slope_rate to rover.slope_rate_after.",
       "Scenario profile; 0 with both rates 0 = the slope input as it is",
       quantity="Time"),
    _V("rover.slope_rate", "rad/s", 0.0, -0.1, 0.1,
       "Input profile: the slope the rover sees is the input slope plus slope_rate*t up to "
       "rover.ramp_time, then slope_rate_after per second, that ramp kept within "
       "+-rover.slope_bound.", "Scenario profile (0: no ramp)", quantity="AngularVelocity"),
    _V("rover.slope_rate_after", "rad/s", 0.0, -0.1, 0.1,
       "Input profile: the slope's rate after rover.ramp_time.", "Scenario profile (0: none)",
       quantity="AngularVelocity"),
    _V("rover.slope_bound", "rad", 1.2, 0.0, 1.2,
       "Input profile: the ramp (not the input) is kept within +-this.",
       "Scenario profile; 1.2 rad: no bound within the slope input's range", quantity="Angle",
       display_unit="deg"),
    _V("rover.towing_rate", "N/s", 0.0, -1.0e3, 1.0e3,
       "Input profile: the towing force the rover pulls is the input towing_force plus "
       "towing_rate*t (a pull test).", "Scenario profile (0: no ramp)"),
    _V("rover.motor_torque_limit", "N.m", 5.0, 1.0e-3, 1.0e4,
       "Largest torque a wheel motor delivers, either sign (the speed loops saturate there; "
       "the integrator stops while saturated).",
       f"{_ASSUMED}: a small geared DC motor", quantity="Torque"),
    *(_V(f"rover.grouser_phase.{wheel}", "rad", phase, 0.0, 2 * math.pi,
         f"Where the {wheel.replace('_', ' ')} wheel's grousers stand at the start, as a phase "
         "of its grouser ripple (2*pi: one grouser pitch): added to its WheelTerrain's "
         "ripple.phase (in an SSP, that wheel's binding; the chassis does not use it). "
         "Unused with the ripple off.",
         "Assumption: wheels mounted independently have no reason to start aligned; the "
         "four spread evenly over one grouser pitch (left and right opposed, front and rear "
         "a quarter apart), so that the ripples do not beat in phase. The rover's limits "
         "report their band over every alignment (docs/rover.md)",
         quantity="Angle", display_unit="deg")
      for wheel, phase in (("front_left", 0.0), ("front_right", math.pi),
                           ("rear_left", math.pi / 2), ("rear_right", 3 * math.pi / 2))),
)


# --- a terrain map along the path (Terrain.fmu): its soil is the soil rows above, and a patch ---


def _patch_row(p: Parameter) -> Parameter:
    """The soil row ``p`` inside the map's patch (``soil.phi`` -> ``patch.phi``)."""
    return Parameter(f"patch.{p.name.split('.', 1)[1]}", p.unit, p.default, p.min, p.max,
                     f"Inside the patch [patch.start, patch.end): {p.description}",
                     "Scenario value: the map's second soil (default: the soil row's default)",
                     quantity=p.quantity, display_unit=p.display_unit, plausible=p.plausible,
                     fmu=GROUND_FMU)


GROUND_TABLE: tuple[Parameter, ...] = (
    Parameter("patch.start", "m", 0.0, -1.0e6, 1.0e6,
              "Where along the path the patch begins (its soil: the patch.* rows; elsewhere "
              "the soil.* rows).", "Scenario value", quantity="Length", fmu=GROUND_FMU),
    Parameter("patch.end", "m", 0.0, -1.0e6, 1.0e6,
              "Where along the path the patch ends (exclusive; patch.end <= patch.start: no "
              "patch).", "Scenario value", quantity="Length", fmu=GROUND_FMU),
    Parameter("terrain.cell", "m", 0.005, 0.001, 0.1,
              "Length of a cell of the rut profile along the track: each cell keeps the "
              "deepest rut a wheel left in it at its middle, linear between cells' middles, "
              "and a wheel meets that profile averaged over the leading half of its "
              "terrain.lookahead (at most 10 cells). The track's last 256 cells are remembered "
              "(1.28 m at the default), so the wheels of one track must be closer than that.",
              "Resolution: the rut varies along the track with the grouser passage, "
              "2*pi*R/n_g = 26 mm for the Rashid wheel: five cells per grouser, and less than "
              "a tenth of its 76 mm contact", quantity="Length", display_unit="mm",
              fmu=GROUND_FMU),
    Parameter("terrain.lookahead", "m", 0.05, 0.003, 1.0,
              "How far ahead of its axle a wheel's contact reaches into the rut it runs in "
              "(the front of its contact): the wheel meets the rut averaged from half this "
              "to this ahead of its axle, or over the last 10 cells of that stretch where "
              "it is longer; the rut it leaves is recorded at its axle. At least three "
              "cells (three of the shortest, 1 mm, at least), so that a wheel never meets "
              "its own rut.",
              "Geometry: at most the wheel's radius ahead of the axle (the Rashid wheel's "
              "50 mm)", quantity="Length", display_unit="mm", fmu=GROUND_FMU),
    *(_patch_row(p) for p in TABLE if p.name.startswith("soil.")),
)
ROWS: tuple[Parameter, ...] = (*TABLE, *RIG_TABLE, *ROVER_TABLE, *GROUND_TABLE)
"""Every parameter of the project, terrain rows, rig rows, rover rows, terrain-map rows: the one
table."""

INDEX: Mapping[str, int] = MappingProxyType({p.name: k for k, p in enumerate(TABLE)})
BY_NAME: Mapping[str, Parameter] = MappingProxyType({p.name: p for p in TABLE})
NAMES: tuple[str, ...] = tuple(p.name for p in TABLE)
RIG_NAMES: tuple[str, ...] = tuple(p.name for p in RIG_TABLE)
ROVER_NAMES: tuple[str, ...] = tuple(p.name for p in ROVER_TABLE)


def lookup(name: str) -> Parameter:
    """Return the table row of ``name`` or raise ParameterError listing close names."""
    try:
        return BY_NAME[name]
    except KeyError:
        import difflib

        if name in RIG_NAMES:
            raise ParameterError(name, None, "belongs to the rig (SingleWheelRig.fmu), "
                                 "not to the terrain model; the rig cases set it") from None
        if name in ROVER_NAMES:
            raise ParameterError(name, None, "belongs to the rover's chassis "
                                 "(RoverChassis.fmu), not to the terrain model; `wheelterrain "
                                 "rover` sets it") from None

        close = difflib.get_close_matches(name, NAMES, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ParameterError(
            name, None, f"is not a parameter{hint} (`wheelterrain params` lists all)"
        ) from None


class ParameterSet(Mapping[str, float]):
    """A complete, validated assignment of every parameter in :data:`TABLE`.

    Immutable; ``with_values`` returns a modified copy. ``vector()`` gives the values in table
    order, the layout of the CasADi functions' ``p`` input.
    """

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, float] | None = None) -> None:
        merged = {p.name: float(p.default) for p in TABLE}
        for name, value in (values or {}).items():
            merged[name] = lookup(name).check(value)
        self._values = merged

    def __getitem__(self, name: str) -> float:
        lookup(name)
        return self._values[name]

    def __iter__(self):
        return iter(NAMES)

    def __len__(self) -> int:
        return len(NAMES)

    def with_values(self, values: Mapping[str, float]) -> ParameterSet:
        """A copy with ``values`` overriding; every new value is checked."""
        return ParameterSet({**self._values, **values})

    def vector(self) -> np.ndarray:
        """Values in table order (the CasADi ``p`` input)."""
        return np.array([self._values[n] for n in NAMES], dtype=float)

    def __repr__(self) -> str:
        changed = {k: v for k, v in self._values.items() if v != BY_NAME[k].default}
        return f"ParameterSet({changed})"


def rover_lookup(name: str) -> Parameter:
    """The rover row ``name`` (RoverChassis.fmu), or ParameterError listing close names."""
    for p in ROVER_TABLE:
        if p.name == name:
            return p
    import difflib

    close = difflib.get_close_matches(name, ROVER_NAMES, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise ParameterError(name, None, f"is not a rover parameter{hint}")


def parse_assignments(items: Iterable[str], find=lookup) -> dict[str, float]:
    """Parse ``NAME=VALUE`` strings (the CLI's ``--set``). Angles accept a ``deg`` suffix.
    ``find``: the row of a name (default the terrain table's :func:`lookup`; the rover's
    :func:`rover_lookup`)."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name, text = name.strip(), text.strip()
        if not sep or not name or not text:
            raise ParameterError(item, None, "is not of the form NAME=VALUE (e.g. soil.phi=0.45)")
        param = find(name)
        factor = 1.0
        if text.lower().endswith("deg"):
            if param.unit != "rad":
                raise ParameterError(name, text, f"takes {param.unit}, not deg")
            text, factor = text[:-3].strip(), DEG
        try:
            value = float(text) * factor
        except ValueError:
            raise ParameterError(name, text, f"is not a number; {param.valid_range()}") from None
        out[name] = param.check(value)
    return out
