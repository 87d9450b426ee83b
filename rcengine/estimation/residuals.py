"""Whiteness of a fitted stochastic model's one-step innovations.

Under the model the standardised innovations ε[k] = e[k]/√s[k] are independent N(0, 1). Two
checks with their 95 % bands (Madsen 2008, *Time Series Analysis*, §6.3; the plots CTSM-R and
pySIP show after a fit):

- sample autocorrelation ρ(ℓ), ℓ = 1 … L: each within ±1.96/√N for white noise;
- cumulated periodogram C(f_j) = Σ_{i≤j} I(f_i) / Σ_i I(f_i) over the m Fourier frequencies:
  white noise follows the diagonal j/m within the Kolmogorov–Smirnov band
  ±1.358 / (√(m−1) + 0.12 + 0.11/√(m−1)) (the band of R's ``cpgram``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import binom

BAND_Z = 1.96
KS_95 = 1.358


@dataclass(frozen=True)
class ResidualChecks:
    """acf: ρ(1 … L); acf_band: its 95 % half-width; acf_outside: lags beyond the band;
    acf_allowed: the most lags a white series leaves outside (binomial 95 % quantile);
    cpgram: cumulated periodogram at the Fourier frequencies; cpgram_band: KS half-width;
    cpgram_deviation: largest distance from the diagonal."""

    acf: np.ndarray
    acf_band: float
    acf_outside: int
    acf_allowed: int
    cpgram: np.ndarray
    cpgram_band: float
    cpgram_deviation: float

    @property
    def white(self) -> bool:
        return self.acf_outside <= self.acf_allowed and self.cpgram_deviation <= self.cpgram_band

    def to_dict(self) -> dict:
        return {
            "white": self.white,
            "acf": self.acf.round(4).tolist(),
            "acf_band": self.acf_band,
            "acf_outside": self.acf_outside,
            "acf_allowed": self.acf_allowed,
            "cpgram_band": self.cpgram_band,
            "cpgram_deviation": self.cpgram_deviation,
        }


def residual_checks(standardised: np.ndarray, lags: int) -> ResidualChecks:
    """Autocorrelation (lags 1 … ``lags``) and cumulated periodogram of ε (finite values)."""
    eps = np.asarray(standardised, dtype=float)
    eps = eps[np.isfinite(eps)]
    n = eps.size
    if n < 8:
        raise ValueError(f"{n} innovations are too few for residual checks")
    lags = max(1, min(lags, n // 4))
    x = eps - eps.mean()
    spectrum = np.abs(np.fft.rfft(x, 2 * n)) ** 2
    # The inverse transform of the zero-padded power spectrum is the (biased) autocovariance.
    autocov = np.fft.irfft(spectrum)[: lags + 1]
    acf = autocov[1:] / autocov[0]
    periodogram = np.abs(np.fft.rfft(x)[1 : n // 2 + 1]) ** 2
    m = periodogram.size
    cumulated = np.cumsum(periodogram) / periodogram.sum()
    root = np.sqrt(max(m - 1, 1))
    band = KS_95 / (root + 0.12 + 0.11 / root)
    return ResidualChecks(
        acf=acf,
        acf_band=BAND_Z / np.sqrt(n),
        acf_outside=int(np.sum(np.abs(acf) > BAND_Z / np.sqrt(n))),
        acf_allowed=int(binom.ppf(0.95, lags, 0.05)),
        cpgram=cumulated,
        cpgram_band=float(band),
        cpgram_deviation=float(np.max(np.abs(cumulated - np.arange(1, m + 1) / m))),
    )
