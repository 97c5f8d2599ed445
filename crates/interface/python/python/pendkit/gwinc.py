"""A drop-in for pygwinc's suspension thermal noise, computed by pendkit's 3-D quad.

pygwinc (0.6) computes the suspension thermal noise of one test mass with
``gwinc.noise.suspensionthermal.suspension_thermal(f, sus, sustf)``: a 1-D chain of
longitudinal and vertical stages, with the vertical noise coupled to the beam line by the
angle ``theta`` between local verticals at the two ends of an arm. :func:`suspension_thermal`
here has the same inputs and output, so a pygwinc budget can use pendkit's model of the
quad instead (``examples/python/gwinc_budget.py`` shows a whole aLIGO budget with it).

The settings of the gwinc ``Suspension`` struct are carried into pendkit's model where it
has a parameter for them (:func:`suspension_settings`), and refused, by name, where it has
not (:class:`UnmappedSuspensionSetting`); frequencies above the fibres' first violin mode,
which the bead-free model does not have, raise a :class:`ViolinModeWarning`.
"""

import math
import warnings
from functools import lru_cache
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ._pendkit import Model

#: The bundled pendkit model used unless ``model=`` says otherwise: the aLIGO test-mass
#: quad as built (pygwinc 0.6.2's numbers, tapered fibres, surface and blade losses).
DEFAULT_MODEL = "quad-aligo"
#: The test-mass coordinates of the bundled quads: longitudinal (along the beam) and
#: vertical displacement of the test mass (LIGO names L3_L and L3_V).
LONGITUDINAL, VERTICAL = "x3", "z3"

#: pygwinc 0.6.2 aLIGO's stage lengths (m, ``Suspension.Stage[i].Length``, i = 0 the test
#: mass), which quad-aligo's wires stand for: l3 is the fibre length itself, the steel
#: wires' vertical extents plus their break-offs are these centre-of-mass separations to
#: 1 mm (docs/quad-aligo.md). A stage Length scales that stage's wires by Length / this.
ALIGO_STAGE_LENGTHS = (0.59, 0.341, 0.277, 0.416)
#: Wires per stage of pendkit's quad (test mass first), as ``Stage[i].NWires``.
QUAD_NWIRES = (4, 4, 4, 2)
# per gwinc stage (test mass first): mass, wire length, blade stiffness, wire radius, blade
# thickness, dilution, and the inertias that scale with the mass
_STAGES = (
    ("m3", "l3", None, "r3", None, "dilution_fibre", ("I3x", "I3y", "I3z")),
    ("m2", "l2", "kv_2", "r2", "blade_2_thickness", "dilution_w2", ("I2x", "I2y", "I2z")),
    ("m1", "l1", "kv_1", "r1", "blade_1_thickness", "dilution_w1", ("I1x", "I1y", "I1z")),
    ("mn", "ln", "kv_n", "rn", "blade_n_thickness", "dilution_wn", ("Inx", "Iny", "Inz")),
)
# gwinc material struct -> pendkit prefix, and field -> suffix (pygwinc reads Dissdepth of
# the wire materials only, as 0 where it is missing)
_MATERIALS = (("Silica", "silica", True), ("C70Steel", "steel", True),
              ("MaragingSteel", "maraging", False))
_MATERIAL_FIELDS = (("Rho", "rho"), ("C", "C"), ("K", "K"), ("Alpha", "alpha"),
                    ("dlnEdT", "dlnE_dT"), ("Phi", "phi"), ("Y", "Y"))


class UnmappedSuspensionSetting(ValueError):
    """A setting of the gwinc ``Suspension`` struct that changes pygwinc's suspension
    thermal noise and that pendkit's model has no parameter for; the message names each."""


class ViolinModeWarning(UserWarning):
    """The frequencies reach above the first violin mode of the test-mass fibres, which
    pendkit's bead-free model does not have (``n_beads`` = 0): pygwinc's continuum fibres
    resonate there and pendkit's do not."""


@lru_cache(maxsize=16)
def _stage(model: str, sets: Tuple[str, ...], stage: str):
    # runs of the same model and overrides are shared between calls (a budget calls once
    # per frequency array, and sweeps over temperature reuse nothing else)
    return Model(model, set=list(sets)).run(stage)


@lru_cache(maxsize=16)
def _parameters(model: str, sets: Tuple[str, ...]) -> Dict[str, float]:
    return {p.name: p.value for p in Model(model, set=list(sets)).parameters()}


_MISSING = object()


def _get(struct: Any, *path: str, default: Any = None) -> Any:
    """``struct.a.b`` for ``path = ("a", "b")``, or ``default`` where a field is missing
    (gwinc structs are attribute objects)."""
    for name in path:
        if struct is None:
            return default
        try:
            struct = getattr(struct, name)
        except AttributeError:
            try:
                struct = struct[name]
            except (KeyError, TypeError, IndexError):
                return default
    return struct


def _isnan(value: Any) -> bool:
    try:
        return math.isnan(float(value))
    except (TypeError, ValueError):
        return False


def suspension_settings(sus: Any, model: str = DEFAULT_MODEL) -> List[str]:
    """The pendkit overrides ("NAME=VALUE") that carry the settings of a gwinc
    ``Suspension`` struct into ``model`` (default quad-aligo): only those that differ from
    the model's own values. Raises :class:`UnmappedSuspensionSetting` naming every setting
    pygwinc's suspension thermal noise reads that the model cannot take.

    Mapped (test mass = ``Stage[0]``, then PUM, UIM, top):

    - ``Temp`` -> ``temperature``;
    - ``Stage[i].Mass`` -> ``m3``, ``m2``, ``m1``, ``mn``, and the stage's inertias scaled
      by the same factor (a body of the same shape);
    - ``Stage[i].Length`` -> the stage's wires (``l3``, ``l2``, ``l1``, ``ln``) scaled by
      Length / :data:`ALIGO_STAGE_LENGTHS` (``l3`` = Length itself);
    - ``Stage[i].K``, ``.WireRadius``, ``.Blade``, ``.Dilution`` (a number; NaN keeps the
      model's computed dilution, as pygwinc computes its own) -> ``kv_*``, ``r*``,
      ``blade_*_thickness``, ``dilution_*``;
    - ``FiberType`` 'Tapered' (``Fiber.Radius``, ``.EndRadius``, ``.EndLength`` -> ``r3``,
      ``r3_neck``, ``l3_neck``) or 'Round' (``r3_neck`` = ``r3``);
    - the materials ``Silica``, ``C70Steel``, ``MaragingSteel`` (``Rho``, ``C``, ``K``,
      ``Alpha``, ``dlnEdT``, ``Phi``, ``Y``, ``Dissdepth``) -> ``silica_*``, ``steel_*``,
      ``maraging_*``.

    Refused: ``FiberType`` 'Ribbon', a number of stages other than 4, ``NWires`` other than
    4, 4, 4, 2, blades above the test mass (``Stage[0].K``), a stage ``Temp`` other than
    ``Temp`` (pygwinc's joint temperatures), materials other than the defaults
    (``WireMaterial``, ``BladeMaterial``), and any mapped setting whose parameter ``model``
    lacks. pygwinc's own checks are assertions on bad values; an error rather than a
    warning here because the noise would otherwise silently be another suspension's.
    Fields pygwinc's suspension thermal noise does not read (``Type``, ``BreakStress``,
    ``Silicon``, ``Ribbon`` unless FiberType is 'Ribbon') are not looked at.
    """
    params = _parameters(model, ())
    wanted: Dict[str, Tuple[float, str]] = {}
    refused: List[str] = []

    def want(param: str, value: Any, source: str) -> None:
        if param not in params:
            refused.append(f"{source} (model {model!r} has no parameter {param})")
            return
        wanted[param] = (float(value), source)

    temp = _get(sus, "Temp", default=_MISSING)
    if temp is not _MISSING:
        want("temperature", temp, "Suspension.Temp")

    stages = _get(sus, "Stage", default=None)
    if stages is not None:
        stages = list(stages)
        if len(stages) != len(_STAGES):
            refused.append(f"Suspension.Stage ({len(stages)} stages; pendkit's quad has 4)")
            stages = []
    fibre_type = _get(sus, "FiberType", default=_MISSING)
    for i, stage in enumerate(stages or []):
        mass_p, length_p, k_p, radius_p, blade_p, dilution_p, inertias = _STAGES[i]
        name = f"Suspension.Stage[{i}]"
        mass = _get(stage, "Mass", default=_MISSING)
        if mass is not _MISSING:
            want(mass_p, mass, f"{name}.Mass")
            if mass_p in params and params[mass_p] > 0:
                for inertia in inertias:
                    if inertia in params:
                        want(inertia, params[inertia] * float(mass) / params[mass_p],
                             f"{name}.Mass")
        length = _get(stage, "Length", default=_MISSING)
        if length is not _MISSING and length_p in params:
            want(length_p, params[length_p] * float(length) / ALIGO_STAGE_LENGTHS[i],
                 f"{name}.Length")
        elif length is not _MISSING:
            want(length_p, length, f"{name}.Length")
        k = _get(stage, "K", default=math.nan)
        if k_p is None:
            if not _isnan(k):
                refused.append(f"{name}.K = {k} (blades above the test mass)")
        else:
            want(k_p, k, f"{name}.K")
            blade = _get(stage, "Blade", default=_MISSING)
            if blade is not _MISSING:
                want(blade_p, blade, f"{name}.Blade")
        radius = _get(stage, "WireRadius", default=math.nan)
        if not _isnan(radius):
            want(radius_p, radius, f"{name}.WireRadius")
        elif i == 0:
            fibre_radius = _get(sus, "Fiber", "Radius", default=_MISSING)
            if fibre_radius is not _MISSING:
                want(radius_p, fibre_radius, "Suspension.Fiber.Radius")
        else:
            refused.append(f"{name}.WireRadius = NaN (pygwinc then takes the fibre's radius "
                           "for a steel stage)")
        dilution = _get(stage, "Dilution", default=math.nan)
        if not _isnan(dilution):
            want(dilution_p, dilution, f"{name}.Dilution")
        nwires = _get(stage, "NWires", default=_MISSING)
        if nwires is not _MISSING and int(nwires) != QUAD_NWIRES[i]:
            refused.append(f"{name}.NWires = {nwires} (pendkit's quad has {QUAD_NWIRES[i]})")
        stage_temp = _get(stage, "Temp", default=_MISSING)
        if stage_temp is not _MISSING and (temp is _MISSING or float(stage_temp) != float(temp)):
            refused.append(f"{name}.Temp = {stage_temp} (joint temperatures; pendkit's "
                           "temp_* parameters set whole wire sets)")
        default_wire = "Silica" if i == 0 else "C70Steel"
        for field, default in (("WireMaterial", default_wire), ("WireMaterialUpper", default_wire),
                               ("WireMaterialLower", default_wire),
                               ("BladeMaterial", "MaragingSteel")):
            material = _get(stage, field, default=_MISSING)
            if material is not _MISSING and material != default:
                refused.append(f"{name}.{field} = {material!r} (pendkit's quad: {default})")

    if fibre_type is not _MISSING:
        if fibre_type == "Tapered":
            for field, param in (("EndRadius", "r3_neck"), ("EndLength", "l3_neck")):
                value = _get(sus, "Fiber", field, default=_MISSING)
                if value is not _MISSING:
                    want(param, value, f"Suspension.Fiber.{field}")
        elif fibre_type == "Round":
            radius = wanted.get("r3", (params.get("r3"), ""))[0]
            if radius is not None:
                want("r3_neck", radius, "Suspension.FiberType = 'Round'")
        else:
            refused.append(f"Suspension.FiberType = {fibre_type!r} (pendkit's fibres are round)")

    for struct, prefix, wire in _MATERIALS:
        material = _get(sus, struct, default=None)
        if material is None:
            continue
        fields = _MATERIAL_FIELDS + ((("Dissdepth", "dissdepth"),) if wire else ())
        for field, suffix in fields:
            value = _get(material, field, default=_MISSING)
            if value is _MISSING:
                if field != "Dissdepth":
                    continue
                value = 0.0  # pygwinc: no surface loss where Dissdepth is missing
            want(f"{prefix}_{suffix}", value, f"Suspension.{struct}.{field}")

    if refused:
        raise UnmappedSuspensionSetting(
            f"pendkit.gwinc: model {model!r} cannot take these gwinc Suspension settings: "
            + "; ".join(refused)
        )
    return [
        f"{param}={value!r}"
        for param, (value, _) in wanted.items()
        if not math.isclose(value, params[param], rel_tol=1e-12, abs_tol=0.0)
    ]


def first_violin_mode(model: str = DEFAULT_MODEL, set: Optional[Sequence[str]] = None) -> float:
    """The first violin mode of the test-mass fibres (Hz), as the string formula
    f1 = (1/2L) √(T/μ) gives it for a fibre of length ``l3``, tension ``T3`` and the
    middle's linear density μ = ρ π ``r3``² (pygwinc's continuum fibre also takes the
    middle's density; for aLIGO 490 Hz, LIGO's measured violin modes lie near 500 Hz)."""
    p = _parameters(model, tuple(set or ()))
    mu = p["silica_rho"] * math.pi * p["r3"] ** 2
    return math.sqrt(p["T3"] / mu) / (2 * p["l3"])


def suspension_thermal(
    f: np.ndarray,
    sus: Any = None,
    sustf: Any = None,
    *,
    model: str = DEFAULT_MODEL,
    set: Optional[Sequence[str]] = None,
    stage: str = "2",
    map_sus: bool = True,
) -> np.ndarray:
    """Suspension thermal noise of one suspension: the displacement PSD of the test mass
    along the beam line (m²/Hz) at the frequencies ``f`` (Hz), as pygwinc 0.6's
    ``gwinc.noise.suspensionthermal.suspension_thermal(f, sus, sustf)``.

    Computed by pendkit's 3-D quad (the bundled model ``model``, default ``"quad-aligo"``, at
    ``stage``, default 2: every wire and fibre with stretch, bending and torsion losses and
    dissipation dilution), not from pygwinc's 1-D chain.

    **What of** ``sus`` **is used, and what is refused.** Every setting of the gwinc
    ``Suspension`` struct that pygwinc's term reads and that the model has a parameter for
    is carried into it (:func:`suspension_settings` lists the mapping: ``Temp``, each
    stage's ``Mass``, ``Length``, ``K``, ``WireRadius``, ``Blade``, ``Dilution``, the fibre
    geometry of ``FiberType`` 'Tapered' or 'Round', and the materials), so that changing
    ``sus`` changes the answer as it changes pygwinc's; a setting it cannot take (ribbons,
    other wire counts or materials, per-stage temperatures) raises
    :class:`UnmappedSuspensionSetting` naming it, rather than being silently ignored.
    ``map_sus=False`` takes only ``Temp`` and θ (the model's own suspension, e.g. with
    ``model="quad"``, the 2005 design, whose parameters the aLIGO struct does not fit).
    ``sustf.VHCoupling.theta`` (rad; else ``sus.VHCoupling.theta``, else 0) couples the
    vertical noise to the beam line as pygwinc does: PSD = S_L + θ² S_V, with S_L and S_V
    pendkit's thermal noise of the test mass's longitudinal and vertical displacement
    (``x3``, ``z3``; their correlation, which pygwinc also ignores, left out). ``set`` adds
    pendkit overrides ("NAME=EXPR" strings, e.g. ``["n_beads=20"]``) after the mapped ones.
    ``sus`` and ``sustf`` may be None (then nothing is mapped).

    **Violin modes.** Without beads (``n_beads`` = 0, the default) pendkit's fibres are
    massless effective springs with no violin modes, where pygwinc's continuum fibres have
    them: a :class:`ViolinModeWarning` is issued when ``f`` reaches above the first violin
    mode (:func:`first_violin_mode`, 490 Hz for aLIGO). Below it the missing fibre mass
    already shows: against pygwinc's aLIGO term the ASD ratio is 1.03 at 100 and 200 Hz,
    0.67 at 300 Hz, 0.25 at 400 Hz and 0.007 at 500 Hz, on pygwinc's violin peak.
    ``set=["n_beads=N"]`` gives the fibres mass and violin modes (docs/quad-aligo.md,
    "Beaded fibres"); then no warning.
    """
    freqs = np.asarray(f, dtype=float)
    if map_sus:
        sets = suspension_settings(sus, model) if sus is not None else []
    else:
        temperature = _get(sus, "Temp")
        sets = [] if temperature is None else [f"temperature={float(temperature)!r}"]
    sets.extend(set or [])
    params = _parameters(model, tuple(sets))
    if params.get("n_beads", 0) == 0 and {"r3", "T3", "l3", "silica_rho"} <= params.keys():
        violin = first_violin_mode(model, sets)
        if freqs.size and np.nanmax(freqs) > violin:
            warnings.warn(
                f"pendkit.gwinc: frequencies up to {np.nanmax(freqs):.4g} Hz reach above the "
                f"fibres' first violin mode ({violin:.4g} Hz), which pendkit's bead-free "
                "model does not have (pygwinc's continuum fibres do); set n_beads to give "
                "the fibres violin modes",
                ViolinModeWarning,
                stacklevel=2,
            )
    theta = _get(sustf, "VHCoupling", "theta")
    if theta is None:
        theta = _get(sus, "VHCoupling", "theta")
    theta = 0.0 if theta is None else float(theta)
    result = _stage(model, tuple(sets), stage)
    psd = result.noise(LONGITUDINAL, freqs.ravel()).psd
    if theta != 0.0:
        psd = psd + theta**2 * result.noise(VERTICAL, freqs.ravel()).psd
    return psd.reshape(freqs.shape)
