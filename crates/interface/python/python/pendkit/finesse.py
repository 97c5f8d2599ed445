"""pendkit suspensions as Finesse 3 mechanical components.

:func:`suspension` turns a pendkit model (a bundled model, a case file, a
:class:`pendkit.Model` or a :class:`pendkit.Result`) and a choice of ports into a Finesse 3
component attached to a mirror's mechanical port ``mirror.mech``: the response of the
mirror's motions ``z``, ``pitch``, ``yaw`` to the forces ``F_z``, ``F_pitch``, ``F_yaw``
(and to the ground's motion, and to forces on other stages) is pendkit's transfer function,
evaluated exactly at each frequency Finesse asks for (``method="tf"``, the default), or the
rational response of pendkit's state space (``method="state_space"``). Finesse then adds
what the light does (radiation pressure, optical springs)::

    import finesse, pendkit, pendkit.finesse

    ifo = finesse.Model()
    ifo.parse("m ETM R=0.999995 T=5e-6 Rc=2245")
    quad = pendkit.Model("quad-aligo")
    ifo.add(pendkit.finesse.suspension(quad, ifo.ETM, name="ETM_sus"))

The port mapping (docs/finesse.md says why each sign is what it is). Finesse's mirror frame:
``z`` along the normal out of the mirror's ``p1`` side, ``y`` up, ``x = y × z``; ``pitch`` a
right-handed rotation about ``x``, ``yaw`` about ``y`` (the reading of Finesse 3.0.2's
``Mirror`` tilt factors, reflection off ``p1`` deflecting the beam by +2 ``xbeta`` in x and
−2 ``ybeta`` in y). pendkit's frame: ``x`` along the beam, ``z`` up, pitch about ``y``, yaw
about ``z``, both right-handed (docs/conventions.md). With ``p1_normal="+x"`` (the default:
the ``p1`` face looks along pendkit's +x)

========================  =====================  ======================  ==========
Finesse node              pendkit (quad)         LIGO name               unit
========================  =====================  ======================  ==========
``mech.z``                ``+x3``                ``L3_L``                m
``mech.pitch``            ``+pitch3``            ``L3_P``                rad
``mech.yaw``              ``+yaw3``              ``L3_Y``                rad
``mech.F_z``              ``force:x3``           ``force:L3_L``          N
``mech.F_pitch``          ``force:pitch3``       ``force:L3_P``          N m
``mech.F_yaw``            ``force:yaw3``         ``force:L3_Y``          N m
``gnd.z|pitch|yaw``       ``x00|pitch00|yaw00``  ``GND_L|GND_P|GND_Y``   m, rad
``<port>.F_z|F_pitch|..`` ``force:x2|pitch2|..`` ``force:L2_L|L2_P|..``  N, N m
========================  =====================  ======================  ==========

and with ``p1_normal="-x"`` the ``z`` and ``pitch`` rows (motions and forces, of the mirror,
the ground and the drives alike) change sign, ``yaw`` does not. Every transfer function is
pendkit's times the product of the two rows' signs, so the diagonal ones (``F_pitch`` →
``pitch``, ``gnd.z`` → ``z``) never change sign and the z–pitch cross-couplings keep theirs
in both orientations (the two signs change together).
"""

from __future__ import annotations

import types
from collections import OrderedDict
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ._pendkit import Model, PendkitError, Result

try:  # Finesse 3 (finesse on PyPI, Python >= 3.10)
    import finesse  # noqa: F401
    from finesse.components import NodeDirection, NodeType
    from finesse.components.general import LocalDegreeOfFreedom, MechanicalConnector
    from finesse.components.workspace import ConnectorWorkspace
except ImportError as _missing:  # pragma: no cover - exercised where finesse is absent
    _FINESSE_ERROR: Optional[ImportError] = _missing
    MechanicalConnector = object  # type: ignore[misc,assignment]
else:
    _FINESSE_ERROR = None

#: The Finesse degrees of freedom of a mirror's mechanical port, in order.
DOFS = ("z", "pitch", "yaw")
#: The quad's test mass: pendkit coordinates for Finesse's z, pitch, yaw.
QUAD_TEST_MASS = ("x3", "pitch3", "yaw3")
#: The quad's suspension point (the ground input), same order.
QUAD_GROUND = ("x00", "pitch00", "yaw00")
#: Drive ports for the quad's upper stages (LIGO names), same order.
QUAD_DRIVES = {
    "L2": ("x2", "pitch2", "yaw2"),
    "L1": ("x1", "pitch1", "yaw1"),
    "M0": ("x0", "pitch0", "yaw0"),
}
_METHODS = ("tf", "state_space")


def _require_finesse() -> None:
    if _FINESSE_ERROR is not None:
        raise ImportError(
            "pendkit.finesse needs Finesse 3 (pip install finesse; Python >= 3.10): "
            f"{_FINESSE_ERROR}"
        )


def _signs(p1_normal: str) -> Dict[str, int]:
    if p1_normal in ("+x", "x"):
        return {"z": 1, "pitch": 1, "yaw": 1}
    if p1_normal == "-x":
        return {"z": -1, "pitch": -1, "yaw": 1}
    raise ValueError(
        f"pendkit.finesse.suspension: p1_normal must be '+x' or '-x', not {p1_normal!r}"
    )


def _result(source: Any, stage: str) -> Result:
    if isinstance(source, Result):
        return source
    if isinstance(source, Model):
        return source.run(stage)
    if isinstance(source, str) or hasattr(source, "__fspath__"):
        return Model(source).run(stage)
    raise TypeError(
        "pendkit.finesse.suspension: source must be a pendkit Model, Result, bundled "
        f"model name or case-file path, not {type(source).__name__}"
    )


def _triple(value: Sequence[str], what: str) -> Tuple[str, str, str]:
    names = tuple(value)
    if len(names) != 3 or not all(isinstance(n, str) and n for n in names):
        raise ValueError(
            f"pendkit.finesse.suspension: {what} must be three pendkit coordinate names "
            f"(for z, pitch, yaw), not {value!r}"
        )
    return names  # type: ignore[return-value]


class _Plant:
    """The pendkit side of one suspension: which (Finesse input, Finesse output) pairs
    couple, the pendkit names and sign of each, and their evaluation at a frequency.

    Shared, not copied, when Finesse deep-copies a model (a Result is immutable)."""

    def __init__(self, result: Result, pairs, method: str, damping_frequency: float):
        self.result = result
        self.pairs = pairs  # [(fin_in, fin_out, pk_in, pk_out, sign)]
        self.method = method
        self._cache: "OrderedDict[float, np.ndarray]" = OrderedDict()
        if method == "state_space":
            inputs = list(dict.fromkeys(p[2] for p in pairs))
            outputs = list(dict.fromkeys(p[3] for p in pairs))
            ss = result.state_space(inputs, outputs, damping_frequency=damping_frequency)
            lam, vec = np.linalg.eig(ss.A)
            self._lam = lam
            self._cv = ss.C @ vec
            self._vb = np.linalg.solve(vec, ss.B)
            self._d = ss.D
            self._in = {n: i for i, n in enumerate(inputs)}
            self._out = {n: i for i, n in enumerate(outputs)}

    def __deepcopy__(self, memo):
        return self

    def response(self, f: float) -> np.ndarray:
        """The signed response of every pair at `f` (Hz), in the order of `pairs`."""
        key = float(f)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        if self.method == "tf":
            values = np.array(
                [sign * self.result.tf(pk_in, pk_out, [key])[0]
                 for _, _, pk_in, pk_out, sign in self.pairs]
            )
        else:
            s = 2j * np.pi * key
            h = (self._cv / (s - self._lam)) @ self._vb + self._d
            values = np.array(
                [sign * h[self._out[pk_out], self._in[pk_in]]
                 for _, _, pk_in, pk_out, sign in self.pairs]
            )
        self._cache[key] = values
        if len(self._cache) > 64:
            self._cache.popitem(last=False)
        return values


class _Workspace(ConnectorWorkspace if _FINESSE_ERROR is None else object):  # type: ignore[misc]
    pass


class PendkitSuspension(MechanicalConnector):  # type: ignore[misc,valid-type]
    """A Finesse 3 mechanical component whose force-to-motion and ground-to-motion
    transfer functions are a pendkit model's (made by :func:`suspension`).

    Ports: ``mech`` (the mirror's own ``z``, ``pitch``, ``yaw``, ``F_z``, ``F_pitch``,
    ``F_yaw`` nodes, shared with it), ``gnd`` (the suspension point's ``z``, ``pitch``,
    ``yaw``, inputs) and one port per drive (``F_z``, ``F_pitch``, ``F_yaw`` inputs). Local
    degrees of freedom ``dofs.F_z``, ``dofs.F_pitch``, ``dofs.F_yaw`` (and
    ``dofs.<port>_F_<dof>`` for each drive) read out the mirror's motion.
    """

    def __init__(self, name, mirror, plant_pairs, result, *, method, damping_frequency,
                 drive_ports, ground):
        super().__init__(name, mirror)
        nodes = {f"mech.{n}": getattr(self.mech, n) for n in
                 ("z", "pitch", "yaw", "F_z", "F_pitch", "F_yaw")}
        if ground:
            self._add_port("gnd", NodeType.MECHANICAL)
            for dof in DOFS:
                nodes[f"gnd.{dof}"] = self.gnd._add_node(dof, NodeDirection.BIDIRECTIONAL)
        for port in drive_ports:
            p = self._add_port(port, NodeType.MECHANICAL)
            for dof in DOFS:
                nodes[f"{port}.F_{dof}"] = p._add_node(f"F_{dof}", NodeDirection.BIDIRECTIONAL)
        self._connections = []
        for fin_in, fin_out, *_ in plant_pairs:
            cname = f"{fin_in}__{fin_out}".replace(".", "_")
            self._register_node_coupling(cname, nodes[fin_in], nodes[fin_out])
            self._connections.append(cname)
        self.plant = _Plant(result, plant_pairs, method, damping_frequency)
        self.dofs = types.SimpleNamespace()
        for dof in DOFS:
            setattr(self.dofs, f"F_{dof}", LocalDegreeOfFreedom(
                f"{self.name}.dofs.F_{dof}", None, nodes[f"mech.F_{dof}"], 1,
                AC_OUT=nodes[f"mech.{dof}"]))
            for port in drive_ports:
                setattr(self.dofs, f"{port}_F_{dof}", LocalDegreeOfFreedom(
                    f"{self.name}.dofs.{port}_F_{dof}", None, nodes[f"{port}.F_{dof}"], 1,
                    AC_OUT=nodes[f"mech.{dof}"]))

    @property
    def couplings(self) -> list:
        """The modelled couplings as (Finesse input, Finesse output, pendkit input,
        pendkit output, sign): the Finesse transfer function is sign × pendkit's."""
        return list(self.plant.pairs)

    def tf(self, freqs, input: str, output: str) -> np.ndarray:
        """This component's transfer function from the Finesse node ``input`` to
        ``output`` (names as in :attr:`couplings`, e.g. ``"mech.F_pitch"``,
        ``"mech.pitch"``) at ``freqs`` (Hz), as Finesse is given it."""
        for k, (fin_in, fin_out, *_ ) in enumerate(self.plant.pairs):
            if (fin_in, fin_out) == (input, output):
                return np.array([self.plant.response(f)[k] for f in np.atleast_1d(freqs)])
        raise ValueError(
            f"{self.name}: no coupling from {input!r} to {output!r} (see .couplings)"
        )

    def _get_workspace(self, sim):
        if not sim.signal:
            return None
        ws = _Workspace(self, sim)
        ws.signal.add_fill_function(self._fill, sim.model.fsig.f.is_changing)
        return ws

    def _fill(self, ws):
        values = self.plant.response(ws.sim.model_settings.fsig)
        connections = ws.signal.connections
        for k, cname in enumerate(self._connections):
            idx = getattr(connections, cname + "_idx", -1)
            if idx is None or idx < 0:
                continue  # a node the simulation leaves out
            with ws.sim.signal.component_edge_fill3(ws.owner_id, idx, 0, 0) as mat:
                mat[:] = values[k]


def suspension(
    source: Union[Model, Result, str],
    mirror: Any,
    *,
    name: Optional[str] = None,
    stage: str = "2",
    test_mass: Sequence[str] = QUAD_TEST_MASS,
    ground: Optional[Sequence[str]] = QUAD_GROUND,
    drives: Optional[Mapping[str, Sequence[str]]] = None,
    dofs: Sequence[str] = DOFS,
    cross_couplings: bool = True,
    p1_normal: str = "+x",
    method: str = "tf",
    damping_frequency: float = 1.0,
) -> "PendkitSuspension":
    """A Finesse 3 suspension component for ``mirror`` (a Finesse ``Mirror`` or
    ``Beamsplitter``, or its mechanical port) whose dynamics are pendkit's.

    - ``source``: a :class:`pendkit.Model` (run at ``stage``, default ``"2"``), a
      :class:`pendkit.Result`, or a bundled model name or case-file path.
    - ``test_mass``: the pendkit coordinates of the suspended optic that Finesse's ``z``,
      ``pitch``, ``yaw`` are (default the quad's ``x3``, ``pitch3``, ``yaw3``; for the
      triple ``("x3", "pitch3", "yaw3")`` too, its optic being body 3).
    - ``ground``: the support coordinates behind the ``gnd`` port's ``z``, ``pitch``,
      ``yaw`` inputs (default ``x00``, ``pitch00``, ``yaw00``), or None for no ``gnd`` port.
    - ``drives``: extra force inputs, ``{port: (x, pitch, yaw coordinates)}``, e.g.
      ``{"L2": ("x2", "pitch2", "yaw2")}`` (:data:`QUAD_DRIVES` has the quad's three).
    - ``dofs``: which of Finesse's ``z``, ``pitch``, ``yaw`` the component models (the
      others are left free for another component, or unmodelled); ``cross_couplings=False``
      keeps only the diagonal couplings (``F_pitch`` → ``pitch``, ``gnd.pitch`` →
      ``pitch``, ...).
    - ``p1_normal``: ``"+x"`` (default) when the mirror's ``p1`` face looks along pendkit's
      +x, ``"-x"`` otherwise; sets the signs (module docstring, docs/finesse.md).
    - ``method``: ``"tf"`` (default) evaluates pendkit's exact transfer functions, with the
      model's structural and viscous damping, at each frequency Finesse solves;
      ``"state_space"`` uses the rational response of ``Result.state_space`` (damping made
      viscous at ``damping_frequency``, Hz: exact there and for viscous damping only; the
      ``gnd`` inputs then lack the damping force of the support's own velocity, a relative
      1e-6 at 2 Hz for quad-aligo, as docs/cli.md's ``ss`` says).

    Couplings that are zero at every frequency (blocks the model decouples, e.g. yaw from z
    in a symmetric quad) are left out. Bad names raise ``ValueError`` naming the argument.
    Add the returned component to the Finesse model with ``model.add(...)``.
    """
    _require_finesse()
    if method not in _METHODS:
        raise ValueError(
            f"pendkit.finesse.suspension: method must be one of {_METHODS}, not {method!r}"
        )
    signs = _signs(p1_normal)
    chosen = tuple(dofs)
    bad = [d for d in chosen if d not in DOFS]
    if bad or not chosen or len(set(chosen)) != len(chosen):
        raise ValueError(
            f"pendkit.finesse.suspension: dofs must be distinct names among {DOFS}, not {dofs!r}"
        )
    result = _result(source, stage)
    mass = dict(zip(DOFS, _triple(test_mass, "test_mass")))
    inputs = [(f"mech.F_{d}", f"force:{mass[d]}", d) for d in chosen]
    if ground is not None:
        support = dict(zip(DOFS, _triple(ground, "ground")))
        inputs += [(f"gnd.{d}", support[d], d) for d in chosen]
    drive_ports = []
    for port, coords in (drives or {}).items():
        if not isinstance(port, str) or not port.isidentifier() or port in ("mech", "gnd"):
            raise ValueError(
                f"pendkit.finesse.suspension: drive port name {port!r} must be an "
                "identifier other than 'mech' and 'gnd'"
            )
        coord = dict(zip(DOFS, _triple(coords, f"drives[{port!r}]")))
        inputs += [(f"{port}.F_{d}", f"force:{coord[d]}", d) for d in chosen]
        drive_ports.append(port)
    outputs = [(f"mech.{d}", mass[d], d) for d in chosen]

    probe = [0.1, 1.0, 10.0]  # Hz: where a coupling is tested for being identically zero
    pairs = []
    for fin_in, pk_in, d_in in inputs:
        for fin_out, pk_out, d_out in outputs:
            if not cross_couplings and d_in != d_out:
                continue
            try:
                values = result.tf(pk_in, pk_out, probe)
            except PendkitError as err:
                raise ValueError(
                    f"pendkit.finesse.suspension: {fin_in} -> {fin_out} "
                    f"(pendkit {pk_in} -> {pk_out}): {err}"
                ) from None
            if np.any(values != 0):
                pairs.append((fin_in, fin_out, pk_in, pk_out, signs[d_in] * signs[d_out]))
    if name is None:
        owner = getattr(mirror, "component", mirror)
        name = f"{getattr(owner, 'name', 'mirror')}_sus"
    return PendkitSuspension(
        name, mirror, pairs, result, method=method, damping_frequency=damping_frequency,
        drive_ports=drive_ports, ground=ground is not None,
    )


__all__ = [
    "DOFS",
    "PendkitSuspension",
    "QUAD_DRIVES",
    "QUAD_GROUND",
    "QUAD_TEST_MASS",
    "suspension",
]
