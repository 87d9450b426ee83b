"""The fitted model's output response to extra heat injected at one of its nodes.

A missing effect adds heat θ·s(t) somewhere in the building; what the thermometer sees of it is
s passed through the model's own dynamics from that node to the indoor air. The response is linear
in s, so it is the convolution of s with the node-to-output impulse response, restarted at each
segment of the record (nothing flows across a gap).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import lsq_linear
from scipy.signal import fftconvolve

from rcengine.dataset import Dataset
from rcengine.estimation.objective import Objective
from rcengine.network import RCNetwork
from rcengine.simulate import simulate


def impulse_response(
    network: RCNetwork, params: dict[str, float], node: str, steps: int, step_s: float
) -> np.ndarray:
    """Output response to 1 W held over the first step at ``node``, from rest. [K/W]"""
    probe = network.copy("probe")
    probe.add_heat_input("probe_heat", node)
    compiled = probe.compile()
    u = np.zeros((steps, compiled.n_inputs))
    u[0, compiled.input_names.index("probe_heat")] = 1.0
    rc = compiled.rc_matrices(params)
    return simulate(rc, u, np.zeros((1, compiled.n_states)), step_s)[0]


def node_responses(
    network: RCNetwork, params: dict[str, float], data: Dataset, node: str, heat: np.ndarray
) -> np.ndarray:
    """Output response (T, m) to each column of ``heat`` (T, m) injected at ``node``. [K per W]

    Each segment of ``data`` starts from rest, as a fit with free initial states would see it.
    """
    heat = np.asarray(heat, dtype=float).reshape(len(data), -1)
    longest = max(seg.stop - seg.start for seg in data.segments)
    h = impulse_response(network, params, node, longest, data.step_s)
    out = np.zeros_like(heat)
    for seg in data.segments:
        n = seg.stop - seg.start
        # y[k] = Σ_{i<k} h[k−i]·q[i]: h[0] = 0 because y is the temperature at the step's start.
        out[seg] = fftconvolve(heat[seg], h[:n, None], axes=0)[:n]
    return out


def parameter_sensitivities(
    network: RCNetwork, params: dict[str, float], data: Dataset
) -> np.ndarray:
    """∂y/∂ln p (T, n_params): how the fitted output moves when each parameter changes by 1 %,
    initial states re-profiled. [K]

    A fitted model has bent its parameters to soak up part of a missing effect; regressing the
    residual on these columns as well lets an explanation undo that compensation (one
    Gauss–Newton step) instead of fighting it.
    """
    compiled = network.compile()
    objective = Objective(compiled, data)
    base = objective.trajectory(params).y
    columns = []
    for name in compiled.param_names:
        value = params[name]
        step = 1e-2 * abs(value) if value != 0 else 1e-6
        moved = objective.trajectory({**params, name: value + step}).y
        columns.append((moved - base) * (1e-2 * abs(value) / step if value != 0 else 1.0))
    return np.column_stack(columns)


def explain_residual(
    residual: np.ndarray, candidates: np.ndarray, nuisance: np.ndarray
) -> tuple[np.ndarray, float]:
    """Fit residual ≈ candidates·θ (θ ≥ 0) + nuisance·β (β free) by bounded least squares.

    Returns θ and the share of the residual energy removed beyond what the nuisance columns
    alone remove [0–1].
    """
    ok = np.isfinite(residual) & np.isfinite(candidates).all(1) & np.isfinite(nuisance).all(1)
    r, X, N = residual[ok], candidates[ok], nuisance[ok]
    scale = np.maximum(np.sqrt((X**2).mean(0)), 1e-300)
    n_scale = np.maximum(np.sqrt((N**2).mean(0)), 1e-300)
    A = np.hstack([X / scale, N / n_scale])
    lower = np.r_[np.zeros(X.shape[1]), np.full(N.shape[1], -np.inf)]
    fit = lsq_linear(A, r, bounds=(lower, np.inf), method="bvls")
    alone = lsq_linear(N / n_scale, r).fun if N.shape[1] else r
    sse_alone = float(alone @ alone)
    sse = float(fit.fun @ fit.fun)
    return fit.x[: X.shape[1]] / scale, 1.0 - sse / max(sse_alone, 1e-300)


def on_off_explainer(
    residual: np.ndarray, responses: np.ndarray, nuisance: np.ndarray
) -> Callable[[np.ndarray], float]:
    """For 0/1 weights s (m,), the share of the residual energy, beyond what the nuisance columns
    remove, that θ·responses·s (θ ≥ 0) explains — ``explain_residual`` of the single column
    responses·s, in O(m²) per call once the nuisance is projected out. [0–1]"""
    ok = np.isfinite(residual) & np.isfinite(responses).all(1) & np.isfinite(nuisance).all(1)
    u, sing, _ = np.linalg.svd(nuisance[ok], full_matrices=False)
    basis = u[:, sing > sing.max(initial=0.0) * 1e-10]
    R = responses[ok] - basis @ (basis.T @ responses[ok])
    r = residual[ok] - basis @ (basis.T @ residual[ok])
    along, gram, total = R.T @ r, R.T @ R, max(float(r @ r), 1e-300)

    def explained(weights: np.ndarray) -> float:
        projection, energy = float(weights @ along), float(weights @ gram @ weights)
        return projection**2 / energy / total if projection > 0 and energy > 0 else 0.0

    return explained
