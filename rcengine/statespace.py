"""Discrete-time state-space systems: the one zero-order-hold discretisation of the engine.

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
