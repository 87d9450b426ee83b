"""RC networks as data: heat capacitors, thermal resistors, prescribed temperatures and heat-flow
inputs, compiled to a continuous linear state-space system.

Elements and their equations (thesis §2.2, Eq. 1–2):

- heat capacitor at node i:            C_i dT_i/dt = Σ q_in,i                       [J/K]
- thermal resistor between a and b:    q_ab = (T_a − T_b) / R_ab                     [K/W]
  (a, b are nodes or prescribed temperatures, e.g. the outdoor air ``t_out``)
- heat-flow input into node i:         q = gain · u(t)
  (gain 1 for a flow in W, an area in m² for an irradiance in W/m²)

Collecting the balances gives  C dT/dt = −K T + F u  with C = diag(C_i), K the symmetric conductance
(Laplacian plus boundary) matrix and F the input matrix, hence

    A = −C⁻¹ K,    B = C⁻¹ F,    y = T_output.

A node may be massless (``add_node``, e.g. the air and surface nodes of ISO 13790's 5R1C).
Its balance is algebraic, 0 = −K_sd T_d − K_ss T_s + F_s u, and is eliminated exactly
(Kron reduction):

    K ← K_dd − K_ds K_ss⁻¹ K_sd,    F ← F_d − K_ds K_ss⁻¹ F_s,
    T_s = K_ss⁻¹ (F_s u − K_sd T_d),

which keeps K symmetric, so every compiled network stays a passive RC system with real, negative
eigenvalues (the fast modal simulation relies on this). A massless output gives y = c T_d + d u.

Every element value is ``factor × parameter`` (or a fixed number), so per-area parameters of the
thesis (Table 2.2, e.g. R = r_wall_ext / wall_area) are written once in the model library.
All assembly is vectorised over a population of parameter sets (leading axis S).
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from rcengine.exceptions import ModelError
from rcengine.statespace import DiscreteStateSpace, check_hold, discretize, discretize_foh

Value = str | float  # a parameter name, or a fixed number in SI units


@dataclass(frozen=True)
class Parameter:
    """A named physical parameter with its unit, default bounds and meaning."""

    name: str
    unit: str
    lower: float
    upper: float
    description: str = ""

    def __post_init__(self) -> None:
        if not self.lower <= self.upper:
            raise ModelError(
                f"parameter '{self.name}': lower bound {self.lower} > upper {self.upper}"
            )


@dataclass(frozen=True)
class Capacitor:
    """The heat capacity of a node, C = factor · capacity. [J/K]"""

    node: str
    capacity: Value
    factor: float = 1.0


@dataclass(frozen=True)
class Resistor:
    """A resistance R = factor · resistance between two nodes, or a node and a prescribed
    temperature. [K/W]"""

    a: str
    b: str
    resistance: Value
    factor: float = 1.0


@dataclass(frozen=True)
class HeatInput:
    """Heat q = factor · gain · u of the input signal u, into a node. [W]"""

    signal: str
    node: str
    gain: Value = 1.0
    factor: float = 1.0


@dataclass
class RCNetwork:
    """Mutable description of an RC network; ``compile()`` freezes it into matrices.

    Examples
    --------
    >>> net = RCNetwork("1R1C")
    >>> net.add_parameter(Parameter("r_env", "K/W", 1e-4, 1e-1, "envelope resistance"))
    >>> net.add_parameter(Parameter("c_air", "J/K", 1e5, 1e8, "zone heat capacity"))
    >>> net.add_capacitor("air", "c_air")
    >>> net.add_resistor("air", "t_out", "r_env")
    >>> net.add_heat_input("q_hvac", "air")
    >>> net.set_output("air")
    """

    name: str
    parameters: dict[str, Parameter] = field(default_factory=dict)
    capacitors: list[Capacitor] = field(default_factory=list)
    massless: list[str] = field(default_factory=list)
    temperatures: list[str] = field(default_factory=list)
    resistors: list[Resistor] = field(default_factory=list)
    heat_inputs: list[HeatInput] = field(default_factory=list)
    output: str | None = None
    description: str = ""

    # --- construction -------------------------------------------------------------------------
    def add_parameter(self, parameter: Parameter) -> RCNetwork:
        if parameter.name in self.parameters:
            raise ModelError(f"parameter '{parameter.name}' already exists in {self.name}")
        self.parameters[parameter.name] = parameter
        return self

    def add_capacitor(self, node: str, capacity: Value, factor: float = 1.0) -> RCNetwork:
        """A node with heat capacity ``factor · capacity`` [J/K]: one state of the model."""
        self._check_new_node(node)
        self._check_value(capacity)
        self.capacitors.append(Capacitor(node, capacity, factor))
        return self

    def add_node(self, node: str) -> RCNetwork:
        """A massless node (e.g. an air or surface node whose capacity is neglected)."""
        self._check_new_node(node)
        self.massless.append(node)
        return self

    def _check_new_node(self, node: str) -> None:
        if node in self.nodes or node in self.temperatures:
            raise ModelError(f"node '{node}' already exists in {self.name}")

    def add_temperature(self, signal: str) -> RCNetwork:
        """Declare a prescribed temperature input (a boundary such as ``t_out``). [°C]"""
        if signal in self.nodes:
            raise ModelError(f"'{signal}' is a node of {self.name}, not a prescribed temperature")
        if signal not in self.temperatures:
            self.temperatures.append(signal)
        return self

    def add_resistor(self, a: str, b: str, resistance: Value, factor: float = 1.0) -> RCNetwork:
        """Resistor between two nodes, or a node and a prescribed temperature (declared on use)."""
        if a == b:
            raise ModelError(f"resistor from '{a}' to itself")
        for end in (a, b):
            if end not in self.nodes:
                self.add_temperature(end)
        if a not in self.nodes and b not in self.nodes:
            raise ModelError(f"resistor '{a}'–'{b}' touches no node of {self.name}")
        self._check_value(resistance)
        self.resistors.append(Resistor(a, b, resistance, factor))
        return self

    def add_heat_input(
        self, signal: str, node: str, gain: Value = 1.0, factor: float = 1.0
    ) -> RCNetwork:
        """Inject ``factor · gain · signal`` [W] into ``node``."""
        if node not in self.nodes:
            raise ModelError(f"heat input '{signal}' targets unknown node '{node}'")
        if signal in self.temperatures:
            raise ModelError(f"'{signal}' is already a prescribed temperature")
        self._check_value(gain)
        self.heat_inputs.append(HeatInput(signal, node, gain, factor))
        return self

    def move_heat_input(self, signal: str, from_node: str, to_node: str) -> RCNetwork:
        """Re-route a heat input (e.g. HVAC heat through a new emitter node instead of the air)."""
        if to_node not in self.nodes:
            raise ModelError(f"unknown node '{to_node}' in {self.name}")
        moved = [h for h in self.heat_inputs if h.signal == signal and h.node == from_node]
        if not moved:
            raise ModelError(f"{self.name} has no heat input '{signal}' into '{from_node}'")
        self.heat_inputs = [
            HeatInput(h.signal, to_node, h.gain, h.factor) if h in moved else h
            for h in self.heat_inputs
        ]
        return self

    def neighbours(self, node: str) -> list[str]:
        """Nodes and prescribed temperatures joined to ``node`` by a resistor."""
        return [r.b if r.a == node else r.a for r in self.resistors if node in (r.a, r.b)]

    def set_output(self, node: str) -> RCNetwork:
        if node not in self.nodes:
            raise ModelError(f"output '{node}' is not a node of {self.name}")
        self.output = node
        return self

    def to_dict(self) -> dict:
        """JSON-ready description; ``from_dict`` rebuilds the same network."""
        return {
            "name": self.name,
            "description": self.description,
            "parameters": [asdict(p) for p in self.parameters.values()],
            "capacitors": [asdict(c) for c in self.capacitors],
            "massless": list(self.massless),
            "temperatures": list(self.temperatures),
            "resistors": [asdict(r) for r in self.resistors],
            "heat_inputs": [asdict(h) for h in self.heat_inputs],
            "output": self.output,
        }

    @classmethod
    def from_dict(cls, data: dict) -> RCNetwork:
        try:
            return cls(
                name=data["name"],
                description=data.get("description", ""),
                parameters={p["name"]: Parameter(**p) for p in data["parameters"]},
                capacitors=[Capacitor(**c) for c in data["capacitors"]],
                massless=list(data.get("massless", [])),
                temperatures=list(data["temperatures"]),
                resistors=[Resistor(**r) for r in data["resistors"]],
                heat_inputs=[HeatInput(**h) for h in data["heat_inputs"]],
                output=data["output"],
            )
        except (KeyError, TypeError) as exc:
            raise ModelError(f"invalid network description: {exc}") from exc

    def copy(self, name: str | None = None) -> RCNetwork:
        """A deep copy to extend without touching the original."""
        new = copy.deepcopy(self)
        if name is not None:
            new.name = name
        return new

    def fixed(self, values: dict[str, float], name: str | None = None) -> RCNetwork:
        """A copy with the parameters ``values`` fixed at those numbers (no longer fitted).

        Elements at the ends of their range are left out exactly, as the limits of the network's
        equations: a heat input of zero gain and a resistor of infinite resistance (an open
        circuit) are removed; a capacity of zero makes its node massless; a resistor of zero
        resistance (a short circuit) joins a massless node to its neighbour, which takes its
        resistors and heat inputs. A node no resistor joins to the output any more leaves, with
        the heat into it and the capacitors and resistors beyond it (none of which could reach the
        output), and so does a boundary temperature, a signal or a parameter nothing uses any
        more."""
        unknown = [p for p in values if p not in self.parameters]
        if unknown:
            raise ModelError(f"{self.name} has no parameter(s) {unknown}")

        def value(v: Value) -> Value:
            return float(values[v]) if isinstance(v, str) and v in values else v

        new = self.copy(name)
        used = self._used_parameters()
        for p in values:
            del new.parameters[p]
        capacitors = [replace(c, capacity=value(c.capacity)) for c in new.capacitors]
        new.capacitors = [c for c in capacitors if c.capacity != 0.0]
        new.massless += [c.node for c in capacitors if c.capacity == 0.0]
        new.resistors = [
            replace(r, resistance=value(r.resistance))
            for r in new.resistors
            if value(r.resistance) != np.inf
        ]
        new.heat_inputs = [
            replace(h, gain=value(h.gain)) for h in new.heat_inputs if value(h.gain) != 0.0
        ]
        while shorts := [r for r in new.resistors if r.resistance == 0.0]:
            new._short_circuit(shorts[0])
        new._drop_unconnected()
        for p in used - new._used_parameters():
            new.parameters.pop(p, None)
        elements = [c.capacity for c in new.capacitors] + [r.resistance for r in new.resistors]
        for v in elements + [h.gain for h in new.heat_inputs]:
            new._check_value(v)
        return new

    def _used_parameters(self) -> set[str]:
        values = [c.capacity for c in self.capacitors] + [r.resistance for r in self.resistors]
        return {v for v in values + [h.gain for h in self.heat_inputs] if isinstance(v, str)}

    def _short_circuit(self, short: Resistor) -> None:
        """Join the ends of a zero resistance: a massless end is absorbed by the other."""
        ends = (short.a, short.b)
        if any(end in self.temperatures for end in ends):
            raise ModelError(
                f"{self.name}: a zero resistance between {short.a!r} and {short.b!r} would hold a "
                "node at a prescribed temperature"
            )
        gone = next((e for e in ends if e in self.massless and e != self.output), None)
        if gone is None:
            gone = next((e for e in ends if e in self.massless), None)
        if gone is None:
            raise ModelError(
                f"{self.name}: a zero resistance may only join a massless node to another, not "
                f"{short.a!r} and {short.b!r}, which both have heat capacity"
            )
        kept = short.b if gone == short.a else short.a
        self.resistors.remove(short)
        self.massless.remove(gone)
        rejoined = [
            replace(r, a=kept if r.a == gone else r.a, b=kept if r.b == gone else r.b)
            for r in self.resistors
        ]
        self.resistors = [r for r in rejoined if r.a != r.b]
        self.heat_inputs = [
            replace(h, node=kept) if h.node == gone else h for h in self.heat_inputs
        ]
        if self.output == gone:
            self.output = kept

    def _drop_unconnected(self) -> None:
        """Remove the nodes no resistive path joins to the output (without passing through a
        prescribed temperature, whose value no node changes) and the boundaries nothing touches
        any more: what happens in them can never reach the measured temperature."""
        reached, frontier = {self.output}, [self.output]
        while frontier:
            node = frontier.pop()
            for r in self.resistors:
                other = r.b if r.a == node else r.a if r.b == node else None
                if other is not None and other not in reached:
                    reached.add(other)
                    if other not in self.temperatures:
                        frontier.append(other)
        self.resistors = [r for r in self.resistors if r.a in reached and r.b in reached]
        self.capacitors = [c for c in self.capacitors if c.node in reached]
        self.massless = [n for n in self.massless if n in reached]
        self.heat_inputs = [h for h in self.heat_inputs if h.node in reached]
        self.temperatures = [t for t in self.temperatures if t in reached]

    def _check_value(self, value: Value) -> None:
        if isinstance(value, str):
            if value not in self.parameters:
                raise ModelError(f"unknown parameter '{value}' in {self.name}; add_parameter first")
        elif not np.isfinite(value) or value < 0:
            raise ModelError(f"fixed element value must be finite and ≥ 0, got {value}")

    # --- views ----------------------------------------------------------------------------------
    @property
    def states(self) -> list[str]:
        """Nodes with heat capacity, in state order."""
        return [c.node for c in self.capacitors]

    @property
    def nodes(self) -> list[str]:
        """All nodes: states first, then massless nodes."""
        return self.states + self.massless

    @property
    def signals(self) -> list[str]:
        """Every input signal in B's column order: prescribed temperatures, then heat flows."""
        flows = list(dict.fromkeys(h.signal for h in self.heat_inputs))
        return self.temperatures + flows

    def compile(self) -> CompiledNetwork:
        return CompiledNetwork(self)


class CompiledNetwork:
    """Frozen matrices of an :class:`RCNetwork` as functions of the parameter vector.

    ``rc_matrices(theta)`` returns the reduced conductance form (C, K, F, c, d);
    ``state_space(theta)`` the plain (A, B, C, D). ``theta`` has shape (S, p) in the order of
    ``param_names``; a dict of named values is accepted for a single set.
    """

    def __init__(self, network: RCNetwork):
        if not network.capacitors:
            raise ModelError(f"{network.name} has no heat capacitor")
        if network.output is None:
            raise ModelError(f"{network.name} has no output; call set_output(node)")
        _check_connected(network)
        self.name = network.name
        self.description = network.description
        self.parameters = dict(network.parameters)
        self.param_names = tuple(network.parameters)
        self.state_names = tuple(network.states)
        self.input_names = tuple(network.signals)
        self.output_node = network.output
        self.lower = np.array([p.lower for p in network.parameters.values()])
        self.upper = np.array([p.upper for p in network.parameters.values()])
        self._network = network.copy()
        self._n_nodes = len(network.nodes)
        self._output_full = network.nodes.index(network.output)
        self._build_templates(network)

    @property
    def network(self) -> RCNetwork:
        """A copy of the source network, to extend."""
        return self._network.copy()

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    @property
    def n_inputs(self) -> int:
        return len(self.input_names)

    @property
    def n_params(self) -> int:
        return len(self.param_names)

    def _value_columns(self, values: list[Value], factors: list[float]) -> tuple:
        """Index into theta (−1 for a fixed value), fixed value and multiplier of each element."""
        idx = np.array([self.param_names.index(v) if isinstance(v, str) else -1 for v in values])
        fixed = np.array([0.0 if isinstance(v, str) else float(v) for v in values])
        return idx.astype(int), fixed, np.asarray(factors, dtype=float)

    def _build_templates(self, net: RCNetwork) -> None:
        n, m = self._n_nodes, self.n_inputs
        node = {name: i for i, name in enumerate(net.nodes)}
        signal = {name: k for k, name in enumerate(self.input_names)}
        self._cap = self._value_columns(
            [c.capacity for c in net.capacitors], [c.factor for c in net.capacitors]
        )
        self._res = self._value_columns(
            [r.resistance for r in net.resistors], [r.factor for r in net.resistors]
        )
        self._gain = self._value_columns(
            [h.gain for h in net.heat_inputs], [h.factor for h in net.heat_inputs]
        )
        # Conductance G_r of resistor r enters K and F with a fixed ±1 pattern: K = Σ_r G_r·TK_r.
        self._TK = np.zeros((len(net.resistors), n, n))
        self._TF_res = np.zeros((len(net.resistors), n, m))
        for r, res in enumerate(net.resistors):
            inside = [node[e] for e in (res.a, res.b) if e in node]
            for i in inside:
                self._TK[r, i, i] += 1.0
            if len(inside) == 2:
                i, j = inside
                self._TK[r, i, j] -= 1.0
                self._TK[r, j, i] -= 1.0
            else:
                boundary = res.b if res.a in node else res.a
                self._TF_res[r, inside[0], signal[boundary]] += 1.0
        self._TF_gain = np.zeros((len(net.heat_inputs), n, m))
        for h, inp in enumerate(net.heat_inputs):
            self._TF_gain[h, node[inp.node], signal[inp.signal]] += 1.0

    @staticmethod
    def _values(theta: np.ndarray, columns: tuple) -> np.ndarray:
        idx, fixed, factor = columns
        vals = np.tile(fixed, (theta.shape[0], 1))
        named = idx >= 0
        vals[:, named] = theta[:, idx[named]]
        return vals * factor

    def as_theta(self, params: dict[str, float] | np.ndarray) -> np.ndarray:
        """Parameter dict or array → array of shape (S, p)."""
        if isinstance(params, dict):
            missing = [p for p in self.param_names if p not in params]
            if missing:
                raise ModelError(f"{self.name}: missing parameter value(s) {missing}")
            params = np.array([[params[p] for p in self.param_names]], dtype=float)
        theta = np.atleast_2d(np.asarray(params, dtype=float))
        if theta.ndim != 2 or theta.shape[1] != self.n_params:
            raise ModelError(f"{self.name}: expected {self.n_params} parameters, got {theta.shape}")
        return theta

    def rc_matrices(self, theta: np.ndarray | dict) -> RCMatrices:
        """Reduced conductance form  C dT/dt = −K T + F u,  y = c T + d u."""
        theta = self.as_theta(theta)
        capacity = self._values(theta, self._cap)
        with np.errstate(divide="ignore", invalid="ignore"):
            conductance = 1.0 / self._values(theta, self._res)
        gain = self._values(theta, self._gain)
        K = np.einsum("sr,rij->sij", conductance, self._TK)
        F = np.einsum("sr,rik->sik", conductance, self._TF_res)
        F += np.einsum("sh,hik->sik", gain, self._TF_gain)
        return _reduce(capacity, K, F, self.n_states, self._output_full)

    def state_space(
        self, theta: np.ndarray | dict
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Continuous (A, B, C, D) with shapes (S,n,n) [1/s], (S,n,m), (S,n), (S,m)."""
        rc = self.rc_matrices(theta)
        A = -rc.K / rc.capacity[:, :, None]
        B = rc.F / rc.capacity[:, :, None]
        return A, B, rc.c, rc.d

    def discrete(
        self, params: dict[str, float] | np.ndarray, dt: float, hold: str = "zoh"
    ) -> DiscreteStateSpace:
        """Exact model of one parameter set at step ``dt`` [s], for embedding: the inputs held
        over each step (``"zoh"``) or linear between samples (``"foh"``, whose state is shifted
        by the ramp's response, ``statespace.discretize_foh``)."""
        A, B, C, D = (a[0] for a in self.state_space(self.as_theta(params)[:1]))
        if check_hold(hold) == "foh":
            Ad, Bd, D, _ = discretize_foh(A, B, C, D, dt)
        else:
            Ad, Bd = discretize(A, B, dt)
        return DiscreteStateSpace(Ad, Bd, C, D, float(dt), self.state_names, self.input_names)


@dataclass(frozen=True)
class RCMatrices:
    """A population of RC systems in conductance form (leading axis S).

    capacity (S,n) [J/K]; K (S,n,n) symmetric [W/K]; F (S,n,m); output y = c·T + d·u with
    c (S,n) and d (S,m).
    """

    capacity: np.ndarray
    K: np.ndarray
    F: np.ndarray
    c: np.ndarray
    d: np.ndarray


def _reduce(capacity: np.ndarray, K: np.ndarray, F: np.ndarray, n_dyn: int, out: int) -> RCMatrices:
    """Eliminate massless nodes (indices ≥ n_dyn) by Kron reduction, see the module docstring."""
    S, n = K.shape[:2]
    m = F.shape[2]
    if n == n_dyn:
        c = np.zeros((S, n))
        c[:, out] = 1.0
        return RCMatrices(capacity, K, F, c, np.zeros((S, m)))
    d_, s_ = slice(0, n_dyn), slice(n_dyn, n)
    # X = K_ss⁻¹ [K_sd | F_s]: massless temperatures follow T_s = X_F u − X_K T_d.
    X = np.linalg.solve(K[:, s_, s_], np.concatenate([K[:, s_, d_], F[:, s_, :]], axis=2))
    X_K, X_F = X[..., :n_dyn], X[..., n_dyn:]
    K_red = K[:, d_, d_] - K[:, d_, s_] @ X_K
    F_red = F[:, d_, :] - K[:, d_, s_] @ X_F
    if out < n_dyn:
        c = np.zeros((S, n_dyn))
        c[:, out] = 1.0
        d = np.zeros((S, m))
    else:
        c, d = -X_K[:, out - n_dyn, :], X_F[:, out - n_dyn, :]
    return RCMatrices(capacity, 0.5 * (K_red + np.swapaxes(K_red, 1, 2)), F_red, c, d)


def _check_connected(net: RCNetwork) -> None:
    """Every node must reach a prescribed temperature, else K is singular (no steady state)."""
    reach = set(net.temperatures)
    changed = True
    while changed:
        changed = False
        for r in net.resistors:
            if (r.a in reach) != (r.b in reach):
                reach.update((r.a, r.b))
                changed = True
    floating = [n for n in net.nodes if n not in reach]
    if floating:
        raise ModelError(
            f"{net.name}: node(s) {floating} have no resistive path to a prescribed temperature"
        )
