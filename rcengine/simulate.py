"""Exact, batched simulation of RC networks in modal coordinates.

For an RC network C Ṫ = −K T + F u (C diagonal positive, K symmetric positive semi-definite),
A = −C⁻¹K is similar to the symmetric matrix −C^{-1/2} K C^{-1/2} = −Q Λ Qᵀ. With modal states
z = Qᵀ C^{1/2} T the system decouples:

    ż_i = −λ_i z_i + g_iᵀ u,        G = Qᵀ C^{-1/2} F,

and the zero-order hold over dt is exact per mode (the same discretisation as
:func:`rcengine.statespace.discretize`, only diagonal):

    z_i[k+1] = a_i z_i[k] + b_i g_iᵀ u[k],   a_i = e^{−λ_i dt},  b_i = (1 − a_i)/λ_i.

The time recursion is then one multiply-add per mode and step, vectorised over a population of
parameter sets; its cost is independent of the number of inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .network import RCMatrices

# Elements of a (steps × population × modes) work block; bounds memory for long series.
_BLOCK_ELEMENTS = 100_000
# Populations with at least this many modes in total are scanned step by step (the per-step
# Python overhead is amortised); narrower ones in blocks of _SCAN_BLOCK steps.
_WIDE_POPULATION = 300


def _scan_block(width: int) -> int:
    """Steps per block: long blocks for a single candidate (fewer carries), short otherwise."""
    return 32 if width <= 9 else 8


@dataclass(frozen=True)
class ModalSystem:
    """A population of discretised RC systems in modal form (leading axis S).

    decay (S,n) = a;  input_map (S,n,m) = diag(b)·G;  to_modal (S,n,n) maps T → z;
    output (S,n) maps z → y;  feedthrough (S,m) = d;  valid (S,) false where the set is
    not a passive, finite system (its outputs are NaN and its cost infinite).
    """

    decay: np.ndarray
    input_map: np.ndarray
    to_modal: np.ndarray
    output: np.ndarray
    feedthrough: np.ndarray
    valid: np.ndarray

    @property
    def size(self) -> int:
        return self.decay.shape[0]

    def modal_state(self, temperatures: np.ndarray) -> np.ndarray:
        """Node temperatures (S,n) → modal states (S,n)."""
        return np.einsum("sij,sj->si", self.to_modal, temperatures)


def modal_system(rc: RCMatrices, dt: float) -> ModalSystem:
    """Discretise a population of RC systems exactly (zero-order hold) in modal form."""
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
        hold = np.where(lam * dt > 1e-12, -np.expm1(-lam * dt) / lam, dt)
    QT = np.swapaxes(Q, 1, 2)
    input_map = hold[:, :, None] * (QT @ (scale[:, :, None] * F))
    to_modal = QT * np.sqrt(safe_cap)[:, None, :]
    output = np.einsum("sj,sji->si", rc.c * scale, Q)
    return ModalSystem(decay, input_map, to_modal, output, rc.d, valid)


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
    """The same recursion, L steps at a time for narrow populations.

    Within a block starting from z_b:  z[b+j] = a^j z_b + Σ_{i<j} a^{j−1−i} f[b+i],  a lower-
    triangular Toeplitz product; only the block-to-block carry is a Python loop. Every power of
    a is ≤ 1, so this is as well conditioned as the step-by-step loop.
    """
    steps, S, n = forcing.shape
    L = _scan_block(S * n)
    n_blocks = -(-steps // L)
    padded = np.zeros((n_blocks * L, S, n))
    padded[:steps] = forcing
    f = padded.reshape(n_blocks, L, S, n).transpose(2, 3, 1, 0)  # (S, n, L, blocks)
    lag = np.arange(L + 1)[:, None] - 1 - np.arange(L)[None, :]
    toeplitz = np.where(lag >= 0, decay[:, :, None, None] ** np.maximum(lag, 0), 0.0)
    within = toeplitz @ f  # (S, n, L+1, blocks): zero-start response, row L = block end
    decay_block = decay**L
    carry = np.empty((S, n, n_blocks))
    for b in range(n_blocks):
        carry[:, :, b] = z
        z = decay_block * z + within[:, :, L, b]

    powers = decay[:, :, None] ** np.arange(L)
    states = powers[:, :, :, None] * carry[:, :, None, :] + within[:, :, :L, :]
    states = states.transpose(3, 2, 0, 1).reshape(n_blocks * L, S, n)[:steps]
    # The carry ran on to the padded end; step once from the last real state instead.
    return states, decay * states[-1] + forcing[-1]


def free_response(system: ModalSystem, steps: int, nodes: list[int]) -> np.ndarray:
    """Output response to a unit initial temperature of each node in ``nodes``, zero input.

    Returns O (S, steps, len(nodes)) with O[:, k, j] = y[k] for T[0] = e_{nodes[j]}.
    """
    S = system.size
    gains = system.output[:, :, None] * system.to_modal[:, :, nodes]  # (S, n, j)
    log_decay = np.log(np.maximum(system.decay, 1e-300))
    out = np.empty((S, steps, len(nodes)))
    block = max(1, _BLOCK_ELEMENTS // max(1, S * system.decay.shape[1]))
    for start in range(0, steps, block):
        k = np.arange(start, min(steps, start + block))
        powers = np.exp(log_decay[:, :, None] * k[None, None, :])  # (S, n, t)
        out[:, start : start + k.size, :] = np.swapaxes(powers, 1, 2) @ gains
    return out


def simulate(rc: RCMatrices, u: np.ndarray, x0: np.ndarray, dt: float) -> np.ndarray:
    """Simulate a population of RC systems from node temperatures x0 (S, n) over u (T, m).

    Parameters
    ----------
    rc : the population's matrices, from ``CompiledNetwork.rc_matrices``.
    u : inputs, one row per step, columns in ``CompiledNetwork.input_names`` order.
        [°C for temperatures, W or W/m² for flows]
    x0 : initial node temperatures. [°C]
    dt : step. [s]

    Returns
    -------
    y : (S, T) output temperature at the start of each step. [°C]
    """
    system = modal_system(rc, dt)
    x0 = np.broadcast_to(np.asarray(x0, dtype=float), system.decay.shape)
    return simulate_modal(system, u, system.modal_state(x0))
