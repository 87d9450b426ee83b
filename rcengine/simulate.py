"""Exact, batched simulation of RC networks in modal coordinates.

For an RC network C Ṫ = −K T + F u (C diagonal positive, K symmetric positive semi-definite),
A = −C⁻¹K is similar to the symmetric matrix −C^{-1/2} K C^{-1/2} = −Q Λ Qᵀ. With modal states
z = Qᵀ C^{1/2} T the system decouples:

    ż_i = −λ_i z_i + g_iᵀ u,        G = Qᵀ C^{-1/2} F,

and the zero-order hold over dt is exact per mode (the same discretisation as
:func:`rcengine.statespace.discretize`, only diagonal):

    z_i[k+1] = a_i z_i[k] + b_i g_iᵀ u[k],   a_i = e^{−λ_i dt},  b_i = (1 − a_i)/λ_i.

Inputs sampled at the stamps and linear in between (first-order hold, ``hold="foh"``) add the
ramp's response r_i = ∫₀^dt e^{−λ_i(dt−s)} s/dt ds = (1 − b_i/dt)/λ_i:

    z_i[k+1] = a_i z_i[k] + (b_i − r_i) g_iᵀ u[k] + r_i g_iᵀ u[k+1].

In the state z̃ = z − r·Gu (Franklin, Powell & Workman, *Digital Control*, §6.3.2) this is again
a recursion in u[k] alone, with the input map (b − r + a·r)·G and the output
y = cᵀz̃ + (d + Σ_i c_i r_i g_i)ᵀ u: the same simulator runs either hold.

The time recursion is then one multiply-add per mode and step, vectorised over a population of
parameter sets; its cost is independent of the number of inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rcengine.network import RCMatrices
from rcengine.statespace import check_hold

# Elements of a (steps × population × modes) work block; bounds memory for long series.
_BLOCK_ELEMENTS = 100_000
# Populations with at least this many modes in total are scanned step by step (the per-step
# Python overhead is amortised); narrower ones in blocks of _SCAN_BLOCK steps.
_WIDE_POPULATION = 300
# Steps per block of the two-level scan; 8 is fastest from 1 to ~100 candidates of 3 modes.
_SCAN_BLOCK = 8


@dataclass(frozen=True)
class ModalSystem:
    """A population of discretised RC systems in modal form (leading axis S).

    decay (S,n) = a;  input_map (S,n,m) = diag(b)·G;  to_modal (S,n,n) maps T → z;
    output (S,n) maps z → y;  feedthrough (S,m) = d;  valid (S,) false where the set is
    not a passive, finite system (its outputs are NaN and its cost infinite). First-order hold:
    input_map and feedthrough as in the module doc, and ramp_map (S,n,m) = diag(r)·G, the shift
    of the state z̃ = z − r·Gu.
    """

    decay: np.ndarray
    input_map: np.ndarray
    to_modal: np.ndarray
    output: np.ndarray
    feedthrough: np.ndarray
    valid: np.ndarray
    ramp_map: np.ndarray | None = None

    @property
    def size(self) -> int:
        return self.decay.shape[0]

    def modal_state(self, temperatures: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """Node temperatures (S,n) → modal states (S,n); under first-order hold the recursion's
        state z̃ = z − r·Gu, which needs the inputs u (m,) of that instant."""
        z = np.einsum("sij,sj->si", self.to_modal, temperatures)
        if self.ramp_map is not None and u is not None:
            z = z - self.ramp_map @ np.asarray(u, dtype=float)
        return z


def modal_system(rc: RCMatrices, dt: float, hold: str = "zoh") -> ModalSystem:
    """Discretise a population of RC systems exactly in modal form, the inputs held over each
    step (``"zoh"``, the contract's rows) or linear between samples (``"foh"``, module doc)."""
    check_hold(hold)
    capacity = rc.capacity
    finite = (
        np.isfinite(capacity).all(1)
        & np.isfinite(rc.K).all((1, 2))
        & np.isfinite(rc.F).all((1, 2))
        & np.isfinite(rc.c).all(1)
        & np.isfinite(rc.d).all(1)
        & (capacity > 0).all(1)
    )
    safe_cap = np.where(finite[:, None], capacity, 1.0)
    K = np.where(finite[:, None, None], rc.K, np.eye(rc.K.shape[1]))
    F = np.where(finite[:, None, None], rc.F, 0.0)
    scale = 1.0 / np.sqrt(safe_cap)
    lam, Q = np.linalg.eigh(K * scale[:, :, None] * scale[:, None, :])
    # A passive network has λ ≥ 0; round-off can give −1e-20, but a clearly negative λ is unstable.
    valid = finite & (lam > -1e-12 * np.abs(lam).max(axis=1, initial=0.0)[:, None]).all(1)
    lam = np.maximum(lam, 0.0)
    decay = np.exp(-lam * dt)
    with np.errstate(divide="ignore", invalid="ignore"):
        b = np.where(lam * dt > 1e-12, -np.expm1(-lam * dt) / lam, dt)
    QT = np.swapaxes(Q, 1, 2)
    G = QT @ (scale[:, :, None] * F)
    to_modal = QT * np.sqrt(safe_cap)[:, None, :]
    output = np.einsum("sj,sji->si", rc.c * scale, Q)
    if hold == "zoh":
        return ModalSystem(decay, b[:, :, None] * G, to_modal, output, rc.d, valid)
    ramp = _ramp(lam, b, dt)
    input_map = (b - ramp + decay * ramp)[:, :, None] * G
    feedthrough = rc.d + np.einsum("si,sim->sm", output * ramp, G)
    return ModalSystem(decay, input_map, to_modal, output, feedthrough, valid, ramp[:, :, None] * G)


def _ramp(lam: np.ndarray, b: np.ndarray, dt: float) -> np.ndarray:
    """r = ∫₀^dt e^{−λ(dt−s)} s/dt ds = (1 − b/dt)/λ [s]; its series dt·(½ − λdt/6) where the
    difference would cancel."""
    x = lam * dt
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(x > 1e-4, (1.0 - b / dt) / lam, dt * (0.5 - x / 6.0))


def simulate_modal(system: ModalSystem, u: np.ndarray, z0: np.ndarray) -> np.ndarray:
    """Run the modal recursion over inputs u (T, m) from modal states z0 (S, n).

    Returns the outputs y (S, T): y[k] = output·z[k] + feedthrough·u[k], z[0] = z0.
    """
    u = np.asarray(u, dtype=float)
    steps = u.shape[0]
    S, n = system.decay.shape
    y = np.empty((S, steps))
    z = np.array(z0, dtype=float, copy=True)
    input_map = system.input_map.reshape(S * n, -1).T
    scan = _scan_loop if S * n >= _WIDE_POPULATION else _scan_blocked
    block = max(1, _BLOCK_ELEMENTS // max(1, S * n))
    for start in range(0, steps, block):
        stop = min(steps, start + block)
        forcing = (u[start:stop] @ input_map).reshape(stop - start, S, n)
        states, z = scan(system.decay, forcing, z)
        y[:, start:stop] = (np.swapaxes(states, 0, 1) @ system.output[:, :, None])[:, :, 0]
    y += system.feedthrough @ u.T
    y[~system.valid] = np.nan
    return y


def _scan_loop(decay: np.ndarray, forcing: np.ndarray, z: np.ndarray) -> tuple:
    """z[k+1] = a·z[k] + f[k], one vectorised step at a time; returns states (T,S,n) and z[T]."""
    states = np.empty_like(forcing)
    for k in range(forcing.shape[0]):
        states[k] = z
        z *= decay
        z += forcing[k]
    return states, z


def _scan_blocked(decay: np.ndarray, forcing: np.ndarray, z: np.ndarray) -> tuple:
    """The same recursion in two levels for narrow populations, every loop over a short axis.

    Cut the steps into blocks of L. Within every block at once, from a zero start:
    w[b, j+1] = a·w[b, j] + f[bL+j] (L steps, vectorised over blocks). The block-start states
    then obey c[b+1] = a^L c[b] + e[b], e[b] = a·w[b, L−1] + f[bL+L−1], c[0] = z, a first-order
    recursion solved by a log-depth prefix scan (c[b] += a^{Ld} c[b−d] for d = 1, 2, 4 …;
    Hillis & Steele 1986). Finally z[bL+j] = a^j c[b] + w[b, j]. Every power of a is ≤ 1, so
    this is as well conditioned as the step-by-step loop.
    """
    steps, S, n = forcing.shape
    L = _SCAN_BLOCK
    n_blocks = -(-steps // L)
    if steps % L:
        padded = np.zeros((n_blocks * L, S, n))
        padded[:steps] = forcing
        forcing = padded
    f = forcing.reshape(n_blocks, L, S, n)
    states = np.empty((n_blocks, L, S, n))
    states[:, 0] = 0.0
    for j in range(L - 1):
        np.multiply(states[:, j], decay, out=states[:, j + 1])
        states[:, j + 1] += f[:, j]
    carry = np.empty((n_blocks, S, n))
    carry[0] = z
    np.multiply(states[:-1, L - 1], decay, out=carry[1:])
    carry[1:] += f[:-1, L - 1]
    factor = decay**L
    shift = 1
    while shift < n_blocks:
        # The right-hand side is evaluated before the in-place add: every update of a level
        # reads the previous level, as the prefix scan requires.
        carry[shift:] += factor * carry[:-shift]
        factor = factor * factor
        shift *= 2
    states += decay ** np.arange(L)[:, None, None] * carry[:, None]
    states = states.reshape(n_blocks * L, S, n)[:steps]
    return states, decay * states[-1] + forcing[steps - 1]


def free_response(system: ModalSystem, steps: int, nodes: list[int]) -> np.ndarray:
    """Output response to a unit initial temperature of each node in ``nodes``, zero input.

    Returns O (S, steps, len(nodes)) with O[:, k, j] = y[k] for T[0] = e_{nodes[j]}.
    """
    S = system.size
    gains = system.output[:, None, :] * np.swapaxes(system.to_modal[:, :, nodes], 1, 2)  # (S,j,n)
    log_decay = np.log(np.maximum(system.decay, 1e-300))
    # Filled as (S, j, steps), so each product is contiguous; returned as a (S, steps, j) view.
    out = np.empty((S, len(nodes), steps))
    block = min(steps, max(1, _BLOCK_ELEMENTS // max(1, S * system.decay.shape[1])))
    # a^k for one block's k = 0 … block−1; later blocks scale it by a^start, a multiply where
    # an exponential per element would cost ten times more.
    within = np.exp(log_decay[:, :, None] * np.arange(block)[None, None, :])  # (S, n, block)
    for start in range(0, steps, block):
        size = min(block, steps - start)
        powers = within[:, :, :size]
        if start:
            powers = powers * np.exp(log_decay * start)[:, :, None]
        out[:, :, start : start + size] = gains @ powers
    return np.swapaxes(out, 1, 2)


def simulate(
    rc: RCMatrices, u: np.ndarray, x0: np.ndarray, dt: float, hold: str = "zoh"
) -> np.ndarray:
    """Simulate a population of RC systems from node temperatures x0 (S, n) over u (T, m).

    Parameters
    ----------
    rc : the population's matrices, from ``CompiledNetwork.rc_matrices``.
    u : inputs, one row per step, columns in ``CompiledNetwork.input_names`` order.
        [°C for temperatures, W or W/m² for flows]
    x0 : initial node temperatures. [°C]
    dt : step. [s]
    hold : "zoh" (inputs held over each step) or "foh" (samples, linear in between).

    Returns
    -------
    y : (S, T) output temperature at the start of each step. [°C]
    """
    u = np.asarray(u, dtype=float)
    system = modal_system(rc, dt, hold)
    x0 = np.broadcast_to(np.asarray(x0, dtype=float), system.decay.shape)
    return simulate_modal(system, u, system.modal_state(x0, u[0]))
