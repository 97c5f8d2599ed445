"""Type stubs of pendkit's compiled core (crates/interface/python/src/lib.rs)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Sets = Union[Mapping[str, Union[float, int, str]], Sequence[str], None]
Frequencies = npt.ArrayLike

class PendkitError(ValueError):
    """Bad input or a failed calculation; the message is the command line's one line."""

def models() -> List[Tuple[str, str]]:
    """The bundled models as (name, one-line summary) pairs."""

def log_grid(start: float, stop: float, n: int) -> npt.NDArray[np.float64]:
    """`n` log-spaced frequencies from `start` to `stop` (Hz), both included."""

class Parameter:
    """One resolved parameter."""

    name: str
    value: float
    """Value in `unit`."""
    unit: str
    """SI unit; empty for a pure number."""
    definition: str
    """The expression: the model's default or the override."""
    overridden: bool

class Model:
    """A bundled model or a case file, with parameter overrides."""

    def __init__(
        self, spec: Union[str, os.PathLike[str]], set: Sets = None
    ) -> None:
        """`spec`: a bundled model name or a case-file path (.toml); `set`: overrides as a
        dict {name: value or expression} or a list of "NAME=EXPR" strings."""
    @property
    def name(self) -> str:
        """Case name: the model name or the case file's stem."""
    @property
    def model(self) -> str:
        """The bundled model the case refines."""
    @property
    def description(self) -> Optional[str]: ...
    @property
    def sets(self) -> List[str]:
        """The overrides, as "NAME=EXPR" strings in order."""
    def with_set(self, set: Sets) -> "Model":
        """This model with more overrides applied after its own."""
    def parameters(self) -> List[Parameter]:
        """Every numeric parameter as resolved."""
    def fit(
        self,
        modes: Union[str, "os.PathLike[str]", Sequence[Tuple[Any, ...]]],
        free: List[str],
        *,
        tf: Union[str, "os.PathLike[str]", None] = None,
        stage: Union[str, int, None] = None,
    ) -> Dict[str, Any]:
        """Fits the `free` parameters to measured modes (a CSV path or (label, hz,
        sigma_hz[, shape]) tuples), as `pendkit fit`; a dict of the result."""
    def run(self, stage: Union[str, int, None] = None) -> "Result":
        """Builds the model and runs a stage ("0a", "0b", "1a", "1b", "2"; default "2")."""
    def sensitivities(
        self,
        stage: Union[str, int, None] = None,
        *,
        modes: bool = True,
        tf: Optional[Tuple[str, str]] = None,
        noise: Optional[str] = None,
        freqs: Optional[Frequencies] = None,
        parameters: Optional[Sequence[str]] = None,
        allow_unstable: bool = False,
        differences: bool = False,
    ) -> "Sensitivities":
        """Derivatives of the mode frequencies (and of |H| of `tf` and the noise ASD of
        `noise` at `freqs`, Hz) with respect to the parameters, as `pendkit sensitivity`."""

class Sensitivities:
    """Derivatives of a stage's answers with respect to the parameters."""

    parameters: List[str]
    """The columns."""
    values: npt.NDArray[np.float64]
    """The parameters' values, in `units`."""
    units: List[str]
    modes_hz: npt.NDArray[np.float64]
    """The rows of `dfdp` (Hz)."""
    mode_labels: List[str]
    dfdp: npt.NDArray[np.float64]
    """modes × parameters, Hz per unit of the parameter."""
    freqs: npt.NDArray[np.float64]
    """Hz (the rows of `dtf_abs_dp` and `dnoise_asd_dp`)."""
    tf_abs: Optional[npt.NDArray[np.float64]]
    dtf_abs_dp: Optional[npt.NDArray[np.float64]]
    """frequencies × parameters."""
    noise_asd: Optional[npt.NDArray[np.float64]]
    """m/√Hz or rad/√Hz."""
    dnoise_asd_dp: Optional[npt.NDArray[np.float64]]
    """frequencies × parameters."""
    not_differentiable: List[Tuple[str, str]]
    """Switches and counts left out, with why."""
    exact: List[bool]
    """Per parameter: exact (dual numbers, implicit function theorem) or differenced."""
    warning: Optional[str]

class Modes:
    """Normal modes ascending in ω²."""

    frequencies: npt.NDArray[np.float64]
    """Hz; minus the growth rate for an unstable mode."""
    omega_squared: npt.NDArray[np.float64]
    """rad²/s²; negative for an unstable mode."""
    stable: npt.NDArray[np.bool_]
    labels: List[str]
    """Dominant coordinate of each mode."""
    families: List[str]
    """Degree-of-freedom family of each mode (L, T, V, R, P, Y, violin, other)."""
    coordinates: List[str]
    """Columns of `shapes` and `energy_fractions`."""
    coordinate_units: List[str]
    shapes: npt.NDArray[np.float64]
    """Modes × coordinates, mass-normalised (vᵀ M v = 1), m or rad."""
    energy_fractions: npt.NDArray[np.float64]
    """Modes × coordinates kinetic-energy fractions; rows sum to 1."""
    def __len__(self) -> int: ...

class Noise:
    """Thermal noise at one output."""

    freqs: npt.NDArray[np.float64]
    """Hz."""
    psd: npt.NDArray[np.float64]
    """One-sided PSD, m²/Hz or rad²/Hz."""
    asd: npt.NDArray[np.float64]
    """ASD, m/√Hz or rad/√Hz (`unit`)."""
    psd_by_tag: Dict[str, npt.NDArray[np.float64]]
    """PSD share of each damping tag; they add up to `psd`."""
    asd_by_tag: Dict[str, npt.NDArray[np.float64]]
    unit: str
    temperature: float
    """K."""

class Stability:
    """The stability verdict."""

    stable: bool
    message: Optional[str]
    """The command line's one-line error naming the first growing mode."""
    unstable_modes: List[int]
    """Indices into `Result.modes()`."""
    def __bool__(self) -> bool: ...

class StateSpace:
    """ẋ = A x + B u, y = C x + D u, with names and SI units."""

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
    """Hz at which damping is represented as viscous."""
    def to_control(self) -> Any:
        """A python-control StateSpace with the same matrices and names."""

class Result:
    """One stage of one model: equilibrium, matrices and normal modes."""

    @property
    def stage(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def temperature(self) -> float:
        """K."""
    def parameters(self) -> List[Parameter]: ...
    def equilibrium(self, naming: Optional[str] = None) -> Dict[str, float]:
        """Coordinate values at equilibrium (m or rad)."""
    def modes(self, naming: Optional[str] = None) -> Modes: ...
    def stability(self) -> Stability: ...
    def check_stable(self) -> None:
        """Raises PendkitError if the equilibrium is unstable."""
    def standard_transfer_functions(self) -> List[Tuple[str, str]]: ...
    def transfer_unit(self, input: str, output: str) -> str: ...
    def tf(
        self, input: str, output: str, freqs: Frequencies, *, full: bool = False
    ) -> npt.NDArray[np.complex128]:
        """Transfer function from `input` to `output` at `freqs` (Hz)."""
    def noise(self, output: str, freqs: Frequencies, *, full: bool = False) -> Noise:
        """Thermal noise of a displacement output at `freqs` (Hz)."""
    def state_space(
        self,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        *,
        damping_frequency: float = 1.0,
        naming: Optional[str] = None,
    ) -> StateSpace:
        """State space with damping viscous at `damping_frequency` (Hz)."""
