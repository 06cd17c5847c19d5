"""What real adults of a person's stature (and mass) measure, and a fit's measurements
weighed against it.

A fit reads a body off two silhouettes; where the model could not follow them (a real
person's outline, hair, clothes, a pose the model lacks) its answer cost is high and its
± wide (:mod:`bodyfit.fitter.fit.spreads`). The stature, the sex and, when given, the
mass say much about the same measurements: ANSUR II (6,068 measured adults,
``fitter/data/ansur2_stats.json``) is, per sex, close to a multivariate normal of them,
and conditioned on the stature and mass it gives each measurement a mean ``m_pop`` and
an SD ``s_pop`` (the regression's residual). The fit's value ``m_fit`` with its ±
``s_fit`` (one SD: it holds the truth about 68 % of the time) and that prediction are
combined as two independent Gaussian readings:

    m = (m_fit / s_fit^2 + m_pop / s_pop^2) / (1 / s_fit^2 + 1 / s_pop^2)
    s = (1 / s_fit^2 + 1 / s_pop^2) ^ -1/2

A sound fit (± a few millimetres) keeps its own values; a poor one leans on what the
stature and mass imply. An unknown sex mixes the two sexes' predictions by how likely the
stature (and mass) is under each (moment-matched). The bicep and forearm have no prior:
ANSUR II takes them flexed. The stature is the input itself.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bodyfit.fitter.model_build.body_sample import SEXES, ReferenceStats

__all__ = ["PRIORS", "PRIOR_KEYS", "MeasurementPrior", "combined"]

#: ``FitSettings.measurement_prior``: "ansur" (the default) or "none" (the fit's own).
PRIORS = ("ansur", "none")
#: The measurements the prior applies to (ANSUR II's bicep and forearm are flexed; the
#: stature is the input).
PRIOR_KEYS = ("A", "B", "C", "D", "E", "F", "G", "J", "K", "L", "M", "N", "P")


@dataclasses.dataclass(frozen=True)
class MeasurementPrior:
    """ANSUR II's per-sex normal over ``PRIOR_KEYS``, the stature "O" and ``mass_kg``."""

    stats: ReferenceStats

    @classmethod
    def load(cls) -> "MeasurementPrior":
        return cls(ReferenceStats.load().subset(PRIOR_KEYS + ("O", "mass_kg")))

    def _conditional(self, sex: str, given: dict[str, float]
                     ) -> tuple[np.ndarray, np.ndarray, float]:
        """(mean (k,), SD (k,)) of ``PRIOR_KEYS`` for ``sex`` given ``given`` (key ->
        value: "O" mm, "mass_kg" kg), and the log-density of ``given`` under the sex."""
        st = self.stats
        cov = st.covariance(sex)
        known = [st.keys.index(k) for k in given]
        wanted = [st.keys.index(k) for k in PRIOR_KEYS]
        values = np.array(list(given.values()), float)
        deviation = values - st.mean[sex][known]
        cov_known = cov[np.ix_(known, known)]
        gain = cov[np.ix_(wanted, known)] @ np.linalg.inv(cov_known)
        mean = st.mean[sex][wanted] + gain @ deviation
        variance = np.diag(cov[np.ix_(wanted, wanted)] - gain @ cov[np.ix_(known, wanted)])
        _, logdet = np.linalg.slogdet(cov_known)
        log_density = -0.5 * (deviation @ np.linalg.solve(cov_known, deviation) + logdet)
        return mean, np.sqrt(variance), float(log_density)

    def predict(self, sex: str, stature_mm: float, mass_kg: float | None = None
                ) -> tuple[dict[str, float], dict[str, float]]:
        """(key -> mean mm, key -> SD mm) of ``PRIOR_KEYS`` for a person of ``sex``
        ("female", "male" or "unknown"), stature and, if given, mass.

        Example:
            >>> prior = MeasurementPrior.load()
            >>> mean, sd = prior.predict("male", 1756.0)  # ANSUR II's mean man
            >>> round(mean["K"]), round(sd["K"])  # crotch height
            (846, 24)
        """
        given = {"O": float(stature_mm)}
        if mass_kg is not None:
            given["mass_kg"] = float(mass_kg)
        sexes = SEXES if sex == "unknown" else (sex,)
        parts = [self._conditional(s, given) for s in sexes]
        log_w = np.array([p[2] + np.log(self.stats.n[s]) for p, s in zip(parts, sexes)])
        weights = np.exp(log_w - log_w.max())
        weights /= weights.sum()
        means = np.array([p[0] for p in parts])
        mean = weights @ means
        variance = weights @ (np.array([p[1] for p in parts]) ** 2 + (means - mean) ** 2)
        return (dict(zip(PRIOR_KEYS, mean.tolist())),
                dict(zip(PRIOR_KEYS, np.sqrt(variance).tolist())))


def combined(measurements: dict[str, float], spreads: dict[str, float],
             prior_mean: dict[str, float], prior_sd: dict[str, float]
             ) -> tuple[dict[str, float], dict[str, float]]:
    """The fit's ``measurements`` and ``spreads`` (key -> mm) weighed against the prior's
    (the module docstring), for the keys the prior has; the others as they are.

    Example:
        >>> m, s = combined({"D": 1000.0, "H": 300.0}, {"D": 30.0, "H": 20.0},
        ...                 {"D": 960.0}, {"D": 40.0})
        >>> round(m["D"], 1), round(s["D"], 1), m["H"]
        (985.6, 24.0, 300.0)
    """
    values, sds = dict(measurements), dict(spreads)
    for key, mean in prior_mean.items():
        if key not in values or not np.isfinite(values[key]):
            continue
        fit_precision = 1.0 / max(spreads[key], 1e-6) ** 2
        prior_precision = 1.0 / prior_sd[key] ** 2
        total = fit_precision + prior_precision
        values[key] = (values[key] * fit_precision + mean * prior_precision) / total
        sds[key] = float(np.sqrt(1.0 / total))
    return values, sds
