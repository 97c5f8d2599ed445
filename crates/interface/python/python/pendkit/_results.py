"""pendkit's result types: plain Python objects holding numpy arrays, made by the compiled
core (src/lib.rs). They pickle (module-level dataclasses) and compare by value: two results
are equal when every field is, arrays element by element with NaN equal to NaN, so a result
that went through a worker process equals the one computed here."""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt


def _same(a: Any, b: Any) -> bool:
    """Value equality of two fields: arrays by dtype, shape and elements (NaN equal to
    NaN), dicts by keys and values, lists and tuples item by item."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)):
            return False
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(
            _same(x, y) for x, y in zip(a, b)
        )
    return bool(a == b)


class _ByValue:
    """Equality field by field (`_same`); unhashable, as the arrays are mutable."""

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(
            _same(getattr(self, f.name), getattr(other, f.name))
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
        )

    __hash__ = None  # type: ignore[assignment]


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One parameter as resolved: `name`, `value` (in `unit`), `unit` (SI; empty for a pure
    number), `definition` (the expression: the model's default or the override) and
    `overridden` (whether an override set it)."""

    name: str
    value: float
    unit: str
    definition: str
    overridden: bool


@dataclasses.dataclass(frozen=True, eq=False)
class Modes(_ByValue):
    """Normal modes, ascending in ω²: `frequencies` (Hz; minus the growth rate for an
    unstable mode), `omega_squared` (rad²/s²), `stable` (bool per mode), `labels` (dominant
    coordinate), `families` (degree-of-freedom family), `coordinates` and
    `coordinate_units` (the columns of the next two), `shapes` (modes × coordinates,
    mass-normalised, m or rad) and `energy_fractions` (modes × coordinates, rows sum to 1)."""

    frequencies: npt.NDArray[np.float64]
    omega_squared: npt.NDArray[np.float64]
    stable: npt.NDArray[np.bool_]
    labels: List[str]
    families: List[str]
    coordinates: List[str]
    coordinate_units: List[str]
    shapes: npt.NDArray[np.float64]
    energy_fractions: npt.NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.labels)

    def __repr__(self) -> str:
        return (f"<pendkit.Modes: {len(self.labels)} modes over "
                f"{len(self.coordinates)} coordinates>")


@dataclasses.dataclass(frozen=True, eq=False)
class Noise(_ByValue):
    """Thermal noise: `freqs` (Hz), `psd` (one-sided, m²/Hz or rad²/Hz), `asd` (m/√Hz or
    rad/√Hz, `unit`), `psd_by_tag` and `asd_by_tag` (dicts tag → numpy array; the PSDs add
    up to `psd`), `temperature` (K)."""

    freqs: npt.NDArray[np.float64]
    psd: npt.NDArray[np.float64]
    asd: npt.NDArray[np.float64]
    psd_by_tag: Dict[str, npt.NDArray[np.float64]]
    asd_by_tag: Dict[str, npt.NDArray[np.float64]]
    unit: str
    temperature: float

    def __repr__(self) -> str:
        return (f"<pendkit.Noise: {len(self.freqs)} frequencies, {len(self.psd_by_tag)} "
                f"tags, ASD in {self.unit}>")


@dataclasses.dataclass(frozen=True, eq=False)
class Stability(_ByValue):
    """The stability verdict: `stable` (no mode with ω² < 0), `message` (the command
    line's one-line error naming the first growing mode, or None) and `unstable_modes`
    (indices into `Result.modes()`). True when stable."""

    stable: bool
    message: Optional[str]
    unstable_modes: List[int]

    def __bool__(self) -> bool:
        return self.stable

    def __repr__(self) -> str:
        if self.message is None:
            return "Stability(stable=True)"
        return f"Stability(stable=False, message={self.message!r})"


def control_name(name: str) -> str:
    """The name a signal or state has in python-control (`StateSpace.to_control`): the
    state space's name with `force:` written `force_` and every other character that
    cannot be in a Python identifier written `_`, so that `control.interconnect` takes it
    by name: `force:x0` → `force_x0`, `force:M0_L` → `force_M0_L`; `x3`, `L3_L` and
    `x0_dot` stay as they are."""
    if name.startswith("force:"):
        name = "force_" + name[len("force:"):]
    name = re.sub(r"[^0-9A-Za-z_]", "_", name)
    return "_" + name if name[:1].isdigit() else name


def _control_names(kind: str, names: List[str]) -> List[str]:
    out = [control_name(n) for n in names]
    seen: Dict[str, str] = {}
    for original, new in zip(names, out):
        if new in seen:
            from ._pendkit import PendkitError

            raise PendkitError(
                f"{kind} '{seen[new]}' and '{original}' both become '{new}' in python-control"
            )
        seen[new] = original
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class StateSpace(_ByValue):
    """A state space ẋ = A x + B u, y = C x + D u: `A`, `B`, `C`, `D` (numpy), the names
    `states`, `inputs`, `outputs` and their SI units, and `damping_frequency` (Hz).
    `to_control()` makes a python-control `StateSpace` with the same matrices and names
    (as `control_name` writes them)."""

    A: npt.NDArray[np.float64]
    B: npt.NDArray[np.float64]
    C: npt.NDArray[np.float64]
    D: npt.NDArray[np.float64]
    states: List[str]
    inputs: List[str]
    outputs: List[str]
    state_units: List[str]
    input_units: List[str]
    output_units: List[str]
    damping_frequency: float

    def to_control(self, name: Optional[str] = None) -> Any:
        """A python-control `StateSpace` (`control.ss`) with these matrices, its inputs,
        outputs and states named as `control_name` writes them (valid identifiers, so
        `control.interconnect` connects them by name), and the system name `name`; needs
        python-control (`pip install "pendkit[control]"`)."""
        try:
            import control  # type: ignore[import-untyped,unused-ignore]
        except ImportError as e:
            raise ImportError(
                f"to_control needs python-control (pip install control): {e}"
            ) from e
        kwargs: Dict[str, Any] = {
            "inputs": _control_names("input", self.inputs),
            "outputs": _control_names("output", self.outputs),
            "states": _control_names("state", self.states),
        }
        if name is not None:
            kwargs["name"] = name
        return control.ss(self.A, self.B, self.C, self.D, **kwargs)

    def __repr__(self) -> str:
        return (f"<pendkit.StateSpace: {len(self.states)} states, {len(self.inputs)} "
                f"inputs, {len(self.outputs)} outputs, damping viscous at "
                f"{self.damping_frequency} Hz>")


@dataclasses.dataclass(frozen=True, eq=False)
class Sensitivities(_ByValue):
    """Derivatives of a stage's answers with respect to the parameters
    (`Model.sensitivities`): `parameters`, `values`, `units` (the columns), `modes_hz` and
    `mode_labels` (the rows of `dfdp`), `dfdp` (modes × parameters, Hz per unit of the
    parameter; no rows when the modes were not asked for), `freqs` (Hz), `tf_abs` and
    `dtf_abs_dp` (frequencies × parameters), `noise_asd` and `dnoise_asd_dp` (None unless
    asked for), `not_differentiable` ((name, why) of switches and counts left out), `exact`
    (per parameter: its mode sensitivities differentiated exactly by dual numbers and the
    implicit function theorem, or exactly 0 for a parameter nothing or only the loss angles
    read, else by differences of the stage's matrices; the |H| and noise sensitivities are
    always differenced) and `warning`."""

    parameters: List[str]
    values: npt.NDArray[np.float64]
    units: List[str]
    modes_hz: npt.NDArray[np.float64]
    mode_labels: List[str]
    dfdp: npt.NDArray[np.float64]
    freqs: npt.NDArray[np.float64]
    tf_abs: Optional[npt.NDArray[np.float64]]
    dtf_abs_dp: Optional[npt.NDArray[np.float64]]
    noise_asd: Optional[npt.NDArray[np.float64]]
    dnoise_asd_dp: Optional[npt.NDArray[np.float64]]
    not_differentiable: List[Tuple[str, str]]
    exact: List[bool]
    warning: Optional[str]

    def __repr__(self) -> str:
        return (f"<pendkit.Sensitivities: {len(self.mode_labels)} modes × "
                f"{len(self.parameters)} parameters>")
