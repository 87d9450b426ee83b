"""Sun the declared glazing cannot pass: the evidence for the opaque envelope's sun, or for
glazing the description leaves out.

Every envelope absorbs sun on its facades and passes a share of it inside; an ordinary one's is
part of what the base model's apertures fit (the declared glazing's g-value, the walls' ``ghi``
aperture). So a margin of test error cannot tell a dark, weakly insulated envelope from an
ordinary one: on the test bed's null buildings the opaque-sun candidate cut the test error as
much as where the facades were dark, with the same fitted α·U (docs/diagnosis.md, "What the data
cannot tell"). A magnitude can. Glass transmits at most ``G_GLAZING_MAX`` of the sun on it
(single clear glass, EN 410). All the sun a fitted model lets into the room — through its
declared glazing and through every other aperture it has (the walls' and the mass's ``ghi``
areas, each passing its steady share to the room) — is read as the g-value the declared glazing
alone would need to admit it (``sun_as_glazing_g``). Where that exceeds glass, the model's
apertures stand in for sun that reaches the room another way: through the opaque envelope (an
ordinary one's share, α·U/h_e of the sun on it, is a few hundredths of a window's per m²) or
through glazing the description leaves out. The windows' g alone beyond glass (the test of the
twentieth session) misses the model that moves that sun into its wall aperture instead.

Where the building declares glazing, the opaque sun is therefore judged on its own here, once the
selection has ended; in the rounds it stands only as a rival to an effect that passes, named when
it explains the same mismatch better (a wind-driven leak can stand in for the sun a windy day's
film strips from a dark facade, and a passing effect is no evidence that the facades are
ordinary). Here, a model that lets in more sun than glass is refitted with all its sun held to
glass (``held_to_glass``), as it is and with each way the excess can come in (the opaque sun,
the window gains by orientation). A way is accepted when, with the sun held to glass, it
forecasts the test period at least as well as the model with impossible apertures did, better
than that model's own apertures can with the sun held to glass, with a training fit the BIC
prefers to theirs (ΔBIC < 0), a non-zero gain and every fitted magnitude plausible for the
building; of two that pass, the one that forecasts the test half better carries the excess
and the other is the runner-up. The impossible sun is the evidence, so the BIC is asked only to
prefer the way, not the rounds' margin; without it, a wall's α·U of 0.1–0.2 W/(m²K) was accepted
where the sun it carried improved the test by 0.5–1 % and the training fit less than its two
parameters cost (ΔBIC +7 to +9 on the dev pool's sky and ventilation cases, against −14 to −100
where the walls were dark). The sun stays held to glass in the model that goes on (its network's
bounds), so the backward check that follows compares every finding with physical apertures.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from rcengine.columns import SOLAR_WINDOW
from rcengine.diagnose.candidates import CANDIDATES, Context, Extension, Skipped
from rcengine.diagnose.declared import has_glazing_g
from rcengine.diagnose.fitting import Fit, FitJob, fit_many
from rcengine.diagnose.plausibility import assess
from rcengine.diagnose.report import Finding, is_idle, judge, reject_implausible
from rcengine.diagnose.screen import screen
from rcengine.models.bounds import G_GLAZING_MAX
from rcengine.models.physical import SOLAR_SIGNALS, solar_apertures
from rcengine.network import RCNetwork

if TYPE_CHECKING:
    from rcengine.diagnose.selection import Problem, Selection

EFFECT = "opaque_solar_gains"
# The ways sun beyond the declared glazing's can reach the room.
EXCESS_EFFECTS = (EFFECT, "window_solar_gains")
# Why the rounds do not name the opaque sun on its own where glazing is declared: it stands there
# only as a rival to an effect that passes (``selection._unrivalled``).
RIVAL_ONLY = (
    "where glazing is declared, the facades' sun is named in a round only when it explains the "
    "mismatch better than another effect that passes (an ordinary envelope's sun cuts the test "
    "error as much as a dark one's), and on its own once the selection has ended, from sun the "
    "model admits beyond what the declared glazing could as glass"
)


def declared_g(network: RCNetwork, params: dict[str, float]) -> float | None:
    """The declared glazing's fitted g-value: the steady share of the sun on it that heats the
    room, into the mass and the air together; None when the model has no declared glazing."""
    if not has_glazing_g(network):
        return None
    return solar_apertures(network, params).get(SOLAR_WINDOW)


def sun_as_glazing_g(fit: Fit) -> float | None:
    """All the sun the fitted model lets into the room, as the g-value the declared glazing
    alone would need to admit it: Σ_k a_k · mean(s_k) / mean(solar_window) over the training
    period, a_k the steady aperture of solar input s_k (its settled heat into the room per unit,
    over the heater's). None without declared glazing. [-]"""
    if not has_glazing_g(fit.network):
        return None
    frame = fit.split.train.frame
    apertures = solar_apertures(fit.network, fit.params)
    window = float(np.nanmean(frame[SOLAR_WINDOW].to_numpy()))
    if window <= 0.0:
        return None
    heat = sum(
        a * float(np.nanmean(frame[k].to_numpy()))
        for k, a in apertures.items()
        if k in SOLAR_SIGNALS
    )
    return heat / window


def sun_parameters(network: RCNetwork) -> list[str]:
    """The fitted gains of the base model's solar heat inputs (its sun apertures: the declared
    glazing's and the envelope's); an extension's, by orientation, are its own finding's."""
    names = {h.gain for h in network.heat_inputs if h.signal in SOLAR_SIGNALS}
    return [n for n in network.parameters if n in names]


def capped_bounds(
    network: RCNetwork, params: dict[str, float], g: float
) -> dict[str, tuple[float, float]]:
    """The network's bounds with all of its sun held to what the declared glazing admits as
    clear glass: each sun aperture (``sun_parameters``) fitted in ``params`` scaled by G_max / g
    from its fitted value (an extension's new ones stay free), ``g`` being the model's sun as a
    glazing g-value (``sun_as_glazing_g``), so that together they admit at most G_max, shared
    between the paths as the fit shared them. [-]"""
    bounds = {name: (p.lower, p.upper) for name, p in network.parameters.items()}
    for name in (n for n in sun_parameters(network) if n in params):
        lower, _ = bounds[name]
        bounds[name] = (lower, max(lower, params[name] * G_GLAZING_MAX / g))
    return bounds


def held_to_glass(network: RCNetwork, params: dict[str, float], g: float) -> RCNetwork:
    """A copy of ``network`` whose sun apertures' bounds are ``capped_bounds``."""
    bounds = capped_bounds(network, params, g)
    held = network.copy(network.name)
    for name, (lower, upper) in bounds.items():
        held.parameters[name] = replace(held.parameters[name], lower=lower, upper=upper)
    return held


def attribute_excess_sun(problem: Problem, state: Selection, ctx: Context) -> bool:
    """After the selection: where the model lets in more sun than the declared glazing could as
    clear glass, refit it with its sun held to glass, as it is and with each way the excess can
    come in (the opaque envelope, glazing the description leaves out); accept the one that
    carries the excess (``ctx``: the current model's candidate context); whether one did."""
    current = state.current
    g = sun_as_glazing_g(current)
    if g is None or g <= G_GLAZING_MAX:
        return False
    exts = []
    for effect in (e for e in EXCESS_EFFECTS if e in problem.settings.effects):
        built = CANDIDATES[effect](ctx)
        if not isinstance(built, Skipped):
            exts.append(built)
    if not exts:
        return False
    names = " or ".join(ext.effect for ext in exts)
    problem.say(
        f"the model lets in as much sun as the declared glazing would at g = {g:.2f}, more than "
        f"glass ({G_GLAZING_MAX:g}): trying {names} with its sun held to glass"
    )
    capped_base, *fits = _capped_fits(problem, current, exts, g)
    findings = [
        _finding(problem, state, ext, fit, capped_base, g)
        for ext, fit in zip(exts, fits, strict=True)
    ]
    _one_carries_it(findings)
    state.skipped.pop(EFFECT, None)
    for finding in findings:
        if finding.accepted:
            state.take(finding)
        elif finding.effect == EFFECT:
            state.verdicts[EFFECT] = finding
        else:
            state.verdicts.setdefault(finding.effect, finding)
    return any(f.accepted for f in findings)


def _one_carries_it(findings: list[Finding]) -> None:
    """Of the findings that pass, the one that forecasts the test half better carries the excess
    (as a round's head to head picks by forecast); each other is rejected with why it lost."""
    passed = [f for f in findings if f.accepted]
    if len(passed) < 2:
        return
    best = min(passed, key=lambda f: f.rmse_test_after)
    for f in passed:
        if f is not best:
            f.accepted = False
            f.reason = (
                f"passed ({f.reason.removeprefix('accepted: ')}), but {best.effect} carries the "
                f"excess sun better (test RMSE {best.rmse_test_after:.3f} K against "
                f"{f.rmse_test_after:.3f} K)"
            )


def _capped_fits(problem: Problem, current: Fit, exts: list[Extension], g: float) -> list[Fit]:
    """The current model and each of ``exts`` refitted with the model's sun held to glass
    (``held_to_glass``), warm-started from the current fit with its sun scaled down to glass."""
    settings = problem.settings
    models = [(current.network, current.options, {})]
    models += [(ext.network, ext.signals, ext.neutral) for ext in exts]
    capped = sun_parameters(current.network)
    jobs = []
    for network, options, neutral in models:
        network = held_to_glass(network, current.params, g)
        at_cap = {n: network.parameters[n].upper for n in capped}
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
    why = (
        f"the model let in as much sun as the declared glazing would at g = {g:.2f}, more than "
        "glass can"
    )
    finding.reason = (
        f"accepted: {why}; " + "; ".join(text for _, text in checks)
        if finding.accepted
        else f"rejected: {why}; " + "; ".join(text for ok, text in checks if not ok)
    )
    finding.detail["excess_sun"] = {
        "declared_g_before": declared_g(current.network, current.params),
        "declared_g_after": declared_g(fit.network, fit.params),
        "sun_g_before": g,
        "sun_g_after": sun_as_glazing_g(fit),
        "g_max": G_GLAZING_MAX,
        "rmse_test_capped_base": base,
        "delta_bic_capped_base": delta_bic,
    }
    assessment = assess(ext, fit.params)
    reject_implausible(finding, assessment.magnitudes, assessment.problems)
    return finding
