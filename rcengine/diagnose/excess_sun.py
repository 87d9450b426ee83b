"""Sun the declared glazing cannot pass: the evidence for the opaque envelope's sun.

Every envelope absorbs sun on its facades and passes a share of it inside; an ordinary one's is
part of what the base model's apertures fit (the declared glazing's g-value, the walls' ``ghi``
aperture). So a margin of test error cannot tell a dark, weakly insulated envelope from an
ordinary one: on the test bed's null buildings the opaque-sun candidate cut the test error as
much as where the facades were dark, with the same fitted α·U (docs/diagnosis.md, "What the data
cannot tell"). A magnitude can. Glass transmits at most ``G_GLAZING_MAX`` of the sun on it
(single clear glass, EN 410); a model whose declared glazing admits more (its steady aperture,
into the mass and the air together) uses the windows as a stand-in for sun that reaches the room
another way. The description's glazing is taken as declared (``declared``), so that way is the
opaque envelope.

Where the building declares glazing, the opaque sun is therefore judged on its own here, once the
selection has ended; in the rounds it stands only as a rival to an effect that passes, named when
it explains the same mismatch better (a wind-driven leak can stand in for the sun a windy day's
film strips from a dark facade, and a passing effect is no evidence that the facades are
ordinary). Here, a model whose declared glazing still admits more sun than glass
is refitted twice with the glazing held to glass (``held_to_glass``), as it is and with the
opaque sun. The opaque sun is accepted when, with physical windows, it forecasts the test period
at least as well as the model with impossible windows did, better than that model's own
apertures can with the windows held to glass, with a training fit the BIC prefers to theirs
(ΔBIC < 0), a non-zero gain and every fitted magnitude plausible for the building. The glazing's
impossible g is the evidence, so the BIC is asked only to prefer the opaque sun, not the rounds'
margin; without it, a wall's α·U of 0.1–0.2 W/(m²K) was accepted where the sun it carried
improved the test by 0.5–1 % and the training fit less than its two parameters cost (ΔBIC +7 to
+9 on the dev pool's sky and ventilation cases, against −14 to −100 where the walls were dark).
The glazing stays held to glass in the model that goes on (its network's bounds), so the
backward check that follows compares every finding with physical windows.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from rcengine.columns import SOLAR_WINDOW
from rcengine.diagnose.candidates import CANDIDATES, Context, Extension, Skipped
from rcengine.diagnose.declared import (
    G_WINDOW,
    G_WINDOW_ADDED_MASS,
    G_WINDOW_AIR,
    has_glazing_g,
)
from rcengine.diagnose.fitting import Fit, FitJob, fit_many
from rcengine.diagnose.plausibility import assess
from rcengine.diagnose.report import Finding, is_idle, judge, reject_implausible
from rcengine.diagnose.screen import screen
from rcengine.models.bounds import G_GLAZING_MAX
from rcengine.models.physical import solar_apertures
from rcengine.network import RCNetwork

if TYPE_CHECKING:
    from rcengine.diagnose.selection import Problem, Selection

EFFECT = "opaque_solar_gains"
DECLARED_G = (G_WINDOW, G_WINDOW_AIR, G_WINDOW_ADDED_MASS)
# Why the rounds do not name the opaque sun on its own where glazing is declared: it stands there
# only as a rival to an effect that passes (``selection._unrivalled``).
RIVAL_ONLY = (
    "where glazing is declared, the facades' sun is named in a round only when it explains the "
    "mismatch better than another effect that passes (an ordinary envelope's sun cuts the test "
    "error as much as a dark one's), and on its own once the selection has ended, from sun the "
    "declared glazing admits beyond glass"
)


def declared_g(network: RCNetwork, params: dict[str, float]) -> float | None:
    """The declared glazing's fitted g-value: the steady share of the sun on it that heats the
    room, into the mass and the air together; None when the model has no declared glazing."""
    if not has_glazing_g(network):
        return None
    return solar_apertures(network, params).get(SOLAR_WINDOW)


def capped_bounds(
    network: RCNetwork, params: dict[str, float], g: float
) -> dict[str, tuple[float, float]]:
    """The network's bounds with the declared glazing's g-values held to clear glass: each
    scaled by G_max / g from its fitted value, so that together they admit at most G_max, split
    between mass and air as the fit split them. [-]"""
    bounds = {name: (p.lower, p.upper) for name, p in network.parameters.items()}
    for name in DECLARED_G:
        if name in bounds:
            lower, _ = bounds[name]
            bounds[name] = (lower, max(lower, params[name] * G_GLAZING_MAX / g))
    return bounds


def held_to_glass(network: RCNetwork, params: dict[str, float], g: float) -> RCNetwork:
    """A copy of ``network`` whose declared glazing's bounds are ``capped_bounds``."""
    bounds = capped_bounds(network, params, g)
    held = network.copy(network.name)
    for name in DECLARED_G:
        if name in held.parameters:
            lower, upper = bounds[name]
            held.parameters[name] = replace(held.parameters[name], lower=lower, upper=upper)
    return held


def attribute_excess_sun(problem: Problem, state: Selection, ctx: Context) -> bool:
    """After the selection: where the model's declared glazing admits more sun than glass,
    refit it held to glass with and without the opaque sun, and accept the opaque sun when it
    carries the excess (``ctx``: the current model's candidate context); whether it did."""
    current = state.current
    g = declared_g(current.network, current.params)
    if g is None or g <= G_GLAZING_MAX or EFFECT not in problem.settings.effects:
        return False
    ext = CANDIDATES[EFFECT](ctx)
    if isinstance(ext, Skipped):
        return False
    problem.say(
        f"the declared glazing admits g = {g:.2f}, more than glass ({G_GLAZING_MAX:g}): "
        f"trying {EFFECT} with the glazing held to glass"
    )
    capped_base, fit = _capped_fits(problem, current, ext, g)
    finding = _finding(problem, state, ext, fit, capped_base, g)
    state.skipped.pop(EFFECT, None)
    if finding.accepted:
        state.take(finding)
    else:
        state.verdicts[EFFECT] = finding
    return finding.accepted


def _capped_fits(problem: Problem, current: Fit, ext: Extension, g: float) -> list[Fit]:
    """The current model and ``ext`` refitted with the declared glazing held to glass
    (``held_to_glass``), warm-started from the current fit with the glazing scaled down to
    glass."""
    settings = problem.settings
    models = [(current.network, current.options, {}), (ext.network, ext.signals, ext.neutral)]
    jobs = []
    for network, options, neutral in models:
        network = held_to_glass(network, current.params, g)
        at_cap = {n: network.parameters[n].upper for n in DECLARED_G if n in network.parameters}
        jobs.append(
            FitJob(
                network,
                options,
                problem.split(network, options),
                settings.preset,
                settings.random_state,
                [{**current.params, **at_cap, **neutral}],
            )
        )
    return fit_many(jobs, settings.workers)


def _finding(
    problem: Problem, state: Selection, ext: Extension, fit: Fit, capped_base: Fit, g: float
) -> Finding:
    """The verdict on the opaque sun refitted with the glazing held to glass (module doc)."""
    current, settings = state.current, problem.settings
    screened = screen(ext, current, fit.split, settings.random_state)
    finding = judge(ext, current, fit, screened, state.round_no + 1, settings, problem.building)
    before, after, base = current.rmse_test, fit.rmse_test, capped_base.rmse_test
    delta_bic = fit.criteria_change(capped_base)["bic"]
    checks = [
        (after <= before, f"test RMSE {before:.3f} → {after:.3f} K with the glazing held to glass"),
        (after < base, f"against {base:.3f} K with the model's own apertures"),
        (delta_bic < 0.0, f"ΔBIC {delta_bic:+.1f} against them"),
        (not is_idle(ext, fit.params), "fitted gain is non-zero"),
    ]
    finding.accepted = all(ok for ok, _ in checks)
    why = f"the declared glazing admitted g = {g:.2f} of its sun, more than glass can"
    finding.reason = (
        f"accepted: {why}; " + "; ".join(text for _, text in checks)
        if finding.accepted
        else f"rejected: {why}; " + "; ".join(text for ok, text in checks if not ok)
    )
    finding.detail["excess_sun"] = {
        "declared_g_before": g,
        "declared_g_after": declared_g(fit.network, fit.params),
        "g_max": G_GLAZING_MAX,
        "rmse_test_capped_base": base,
        "delta_bic_capped_base": delta_bic,
    }
    assessment = assess(ext, fit.params)
    reject_implausible(finding, assessment.magnitudes, assessment.problems)
    return finding
