"""Type stubs of pendkit's compiled core (crates/interface/python/src/lib.rs)."""

import os
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

from ._results import Modes as Modes
from ._results import Noise as Noise
from ._results import Parameter as Parameter
from ._results import Sensitivities as Sensitivities
from ._results import Stability as Stability
from ._results import StateSpace as StateSpace

__version__: str
__all__ = [
    "Model",
    "Modes",
    "Noise",
    "Parameter",
    "PendkitError",
    "Result",
    "Sensitivities",
    "Stability",
    "StateSpace",
    "__version__",
    "_sweep_chunk",
    "log_grid",
    "models",
]

_Number = Union[float, int, np.integer[Any], np.floating[Any], npt.NDArray[Any]]
"""A real number: a Python int or float, a numpy integer or floating scalar, or a 0-d
array of one."""
_Sets = Union[Mapping[str, Union[_Number, str]], Sequence[str], None]
_Frequencies = npt.ArrayLike
_Stage = Union[str, int, np.integer[Any], None]

class PendkitError(ValueError):
    """Bad input or a failed calculation; the message is the command line's one line.
    `pendkit.PendkitError`; it pickles with its message."""

def models() -> List[Tuple[str, str]]:
    """The bundled models as (name, one-line summary) pairs."""

def log_grid(
    start: _Number, stop: _Number, n: Union[int, np.integer[Any]]
) -> npt.NDArray[np.float64]:
    """`n` log-spaced frequencies from `start` to `stop` (Hz), both included."""

@final
class Model:
    """A bundled model or a case file, with parameter overrides."""

    def __new__(
        cls,
        spec: Union[str, os.PathLike[str]],
        set: _Sets = None,
        *,
        _case_text: Optional[str] = None,
    ) -> "Model":
        """`spec`: a bundled model name or a case-file path (.toml); `set`: overrides as a
        dict {name: value or expression} (a real number is taken as its exact value) or a
        list of "NAME=EXPR" strings."""
    def __eq__(self, other: object, /) -> bool:
        """The same model name (or case-file path and text) and the same overrides, in any
        order."""
    def __hash__(self) -> int: ...
    def __getnewargs_ex__(self) -> Tuple[Tuple[str], Dict[str, Any]]:
        """What rebuilds the model in another process (pickle)."""
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
    def with_set(self, set: _Sets) -> "Model":
        """This model with more overrides applied after its own."""
    def parameters(self) -> List[Parameter]:
        """Every numeric parameter as resolved."""
    def fit(
        self,
        modes: Union[str, "os.PathLike[str]", Sequence[Tuple[Any, ...]]],
        free: Sequence[str],
        *,
        tf: Union[str, "os.PathLike[str]", None] = None,
        stage: _Stage = None,
        jacobian: Literal["exact", "differences"] = "exact",
        starts: int = 1,
        more_starts: int = 4,
    ) -> Dict[str, Any]:
        """Fits the `free` parameters to measured modes (a CSV path or (label, hz,
        sigma_hz[, shape]) tuples), as `pendkit fit` (`starts`, `more_starts` as
        `--starts`, `--more-starts`); a dict of the result."""
    def run(
        self,
        stage: _Stage = None,
        fibres: Union[Literal["static", "continuum"], Sequence[str], None] = None,
    ) -> "Result":
        """Builds the model and runs a stage ("0a", "0b", "1a", "1b", "2"; default "2");
        ``fibres`` as the command line's ``--fibres`` ("static", "continuum", wire names;
        ``None``: as the model's file says)."""
    def sensitivities(
        self,
        stage: _Stage = None,
        *,
        modes: bool = True,
        tf: Optional[Tuple[str, str]] = None,
        noise: Optional[str] = None,
        freqs: Optional[_Frequencies] = None,
        parameters: Optional[Sequence[str]] = None,
        allow_unstable: bool = False,
        differences: bool = False,
    ) -> "Sensitivities":
        """Derivatives of the mode frequencies (and of |H| of `tf` and the noise ASD of
        `noise` at `freqs`, Hz) with respect to the parameters, as `pendkit sensitivity`."""

@final
class Result:
    """One stage of one model: equilibrium, matrices and normal modes. Pickles as its model
    and stage (computed again when unpickled); equal when the models and stages are."""

    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> Tuple[Any, Tuple[str]]:
        """`Model.run` of the model, with the stage (pickle)."""
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
        self, input: str, output: str, freqs: _Frequencies, *, full: bool = False
    ) -> npt.NDArray[np.complex128]:
        """Transfer function from `input` to `output` at `freqs` (Hz)."""
    def noise(self, output: str, freqs: _Frequencies, *, full: bool = False) -> Noise:
        """Thermal noise of a displacement output at `freqs` (Hz)."""
    def state_space(
        self,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        *,
        damping_frequency: _Number = 1.0,
        naming: Optional[str] = None,
    ) -> StateSpace:
        """State space with damping viscous at `damping_frequency` (Hz); `outputs` are
        outputs or states (`x0_dot`, a velocity)."""
    def to_control(
        self,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        *,
        damping_frequency: _Number = 1.0,
        naming: Optional[str] = None,
        name: Optional[str] = None,
    ) -> Any:
        """`state_space(...).to_control(name)`: a python-control StateSpace whose signals
        and states are named as valid identifiers (`force:x0` → `force_x0`)."""

def _sweep_chunk(
    model: Model,
    names: List[str],
    values: npt.NDArray[np.float64],
    what: str,
    *,
    input: Optional[str] = None,
    output: Optional[str] = None,
    freqs: Optional[_Frequencies] = None,
    stage: _Stage = None,
) -> Tuple[npt.NDArray[Any], List[Tuple[int, str]]]:
    """One chunk of `pendkit.sweep`: the rows (NaN where a point failed) and the failures."""
