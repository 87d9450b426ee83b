"""Discrete-time state-space systems: the engine's exact discretisations (zero- and first-order
hold, ``discretize`` and ``discretize_foh``; with noise, ``discretize_stochastic``).

With the input held constant over a step of length dt (zero-order hold), the exact solution of
ẋ = A x + B u is

    x(t + dt) = e^{A dt} x(t) + (∫₀^dt e^{A τ} dτ) B u(t) = A_d x + B_d u.

Both blocks come from one matrix exponential of the augmented matrix (Van Loan 1978):

    exp( [[A, B], [0, 0]] · dt ) = [[A_d, B_d], [0, I]].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from rcengine.exceptions import ModelError

# How inputs run between samples: held over each step (zero-order hold, the contract's rows) or
# linear between samples (first-order hold).
HOLDS = ("zoh", "foh")


def check_hold(hold: str) -> str:
    """``hold`` if it is one of :data:`HOLDS`; else ModelError naming the choices."""
    if hold not in HOLDS:
        raise ModelError(f"unknown input hold {hold!r}; choose one of {HOLDS}")
    return hold


def discretize(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation, batched over a leading axis.

    Parameters
    ----------
    A : (..., n, n) continuous state matrix. [1/s]
    B : (..., n, m) continuous input matrix. [state unit / (input unit · s)]
    dt : step. [s]

    Returns
    -------
    A_d : (..., n, n) and B_d : (..., n, m), such that x[k+1] = A_d x[k] + B_d u[k].
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n, m = A.shape[-1], B.shape[-1]
    batch = A.shape[:-2]
    M = np.zeros((*batch, n + m, n + m))
    M[..., :n, :n] = A * dt
    M[..., :n, n:] = B * dt
    E = scipy.linalg.expm(M)
    return E[..., :n, :n], E[..., :n, n:]


def discretize_foh(
    A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact first-order-hold discretisation (inputs sampled, linear between samples), in the
    form x̃[k+1] = A_d x̃[k] + B̃ u[k], y[k] = C x̃[k] + D̃ u[k] of one parameter set.

    With Γ₀ the zero-order hold's B_d and Γ₁ = ∫₀^dt e^{A(dt−s)} B s/dt ds the response to the
    ramp, x[k+1] = A_d x[k] + (Γ₀ − Γ₁) u[k] + Γ₁ u[k+1]; in the state x̃ = x − Γ₁ u,
    B̃ = Γ₀ − Γ₁ + A_d Γ₁ and D̃ = D + C Γ₁ (Franklin, Powell & Workman, *Digital Control of
    Dynamic Systems*, §6.3.2). All three blocks come from one exponential:

        exp( [[A, B, 0], [0, 0, I/dt], [0, 0, 0]] · dt ) = [[A_d, Γ₀, Γ₁], [0, I, I], [0, 0, I]].

    Parameters: A (n, n) [1/s], B (n, m), C (n,), D (m,), dt [s]. Returns A_d, B̃ (n, m), D̃ (m,)
    and Γ₁ (n, m), which maps a physical state to the recursion's: x̃ = x − Γ₁ u.
    """
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + 2 * m, n + 2 * m))
    M[:n, :n] = A * dt
    M[:n, n : n + m] = B * dt
    M[n : n + m, n + m :] = np.eye(m)
    E = scipy.linalg.expm(M)
    A_d, gamma0, gamma1 = E[:n, :n], E[:n, n : n + m], E[:n, n + m :]
    return A_d, gamma0 - gamma1 + A_d @ gamma1, D + C @ gamma1, gamma1


def discretize_stochastic(
    A: np.ndarray, B: np.ndarray, diffusion: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact discretisation of dx = (A x + B u) dt + dω, E[dω dωᵀ] = Σ dt, batched.

    The noise gathered over one step is Gaussian with covariance Q_d = ∫₀^dt e^{Aτ} Σ e^{Aᵀτ} dτ.
    Van Loan (1978, Theorem 1) gives it from one matrix exponential; the zero-order hold of B is
    the transpose of the hold above, so one exponential of a (2n + m) block matrix gives all three:

        exp( [[−A, Σ, 0],      [[·, F₁₂,  0],
              [ 0, Aᵀ, 0],  =   [0, A_dᵀ, 0],     Q_d = A_d F₁₂.
              [ 0, Bᵀ, 0]] h)   [0, B_dᵀ, I]]

    (Row block 1 never reaches block 3, so F₁₂ is Van Loan's own.) F₁₂ grows like e^{‖A‖h}
    while A_d shrinks like e^{−‖A‖h}, so the product loses every digit for a stiff network (a
    light air node beside a heavy wall: ‖A‖dt of 50 or more). The exponential is therefore taken
    over h = dt / 2^k with ‖A‖h ≤ ½, and the step doubled k times, each an identity of the
    recursion x ← A_h x + B_h u + w:

        Q_2h = Q_h + A_h Q_h A_hᵀ,   B_2h = B_h + A_h B_h,   A_2h = A_h².

    Parameters
    ----------
    A : (..., n, n) continuous state matrix. [1/s]
    B : (..., n, m) continuous input matrix. [state unit / (input unit · s)]
    diffusion : (..., n, n) Σ, the noise intensity. [state unit² / s]
    dt : step. [s]

    Returns
    -------
    A_d (..., n, n), B_d (..., n, m) as :func:`discretize`, and Q_d (..., n, n), symmetric.
    [state unit² for Q_d]
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n, m = A.shape[-1], B.shape[-1]
    norm = float(np.abs(A).sum(axis=-1).max(initial=0.0)) * dt
    doublings = int(np.ceil(np.log2(norm / 0.5))) if norm > 0.5 else 0
    h = dt / 2.0**doublings
    M = np.zeros((*A.shape[:-2], 2 * n + m, 2 * n + m))
    M[..., :n, :n] = -A * h
    M[..., :n, n : 2 * n] = np.asarray(diffusion, dtype=float) * h
    M[..., n : 2 * n, n : 2 * n] = np.swapaxes(A, -1, -2) * h
    M[..., 2 * n :, n : 2 * n] = np.swapaxes(B, -1, -2) * h
    E = scipy.linalg.expm(M)
    A_d = np.swapaxes(E[..., n : 2 * n, n : 2 * n], -1, -2)
    B_d = np.swapaxes(E[..., 2 * n :, n : 2 * n], -1, -2)
    Q = A_d @ E[..., :n, n : 2 * n]
    for _ in range(doublings):
        Q = Q + A_d @ Q @ np.swapaxes(A_d, -1, -2)
        B_d = B_d + A_d @ B_d
        A_d = A_d @ A_d
    return A_d, B_d, 0.5 * (Q + np.swapaxes(Q, -1, -2))


@dataclass(frozen=True)
class DiscreteStateSpace:
    """x[k+1] = A x[k] + B u[k],  y[k] = C x[k] + D u[k]  for one parameter set.

    Plain arrays plus the step and the names an MPC needs to embed the model.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]

    def __post_init__(self) -> None:
        n, m = self.A.shape[0], self.B.shape[1]
        if self.A.shape != (n, n) or self.B.shape != (n, m):
            raise ValueError(f"inconsistent shapes A {self.A.shape}, B {self.B.shape}")
        if self.C.shape != (n,) or self.D.shape != (m,):
            raise ValueError(f"inconsistent shapes C {self.C.shape}, D {self.D.shape}")
        if len(self.state_names) != n or len(self.input_names) != m:
            raise ValueError("state/input names do not match the matrices")

    def simulate(self, u: np.ndarray, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Plain recursion over u (T, m) from x0 (n,): returns outputs (T,) and states (T+1, n)."""
        u = np.asarray(u, dtype=float)
        x = np.empty((u.shape[0] + 1, self.A.shape[0]))
        x[0] = x0
        for k in range(u.shape[0]):
            x[k + 1] = self.A @ x[k] + self.B @ u[k]
        return x[:-1] @ self.C + u @ self.D, x
