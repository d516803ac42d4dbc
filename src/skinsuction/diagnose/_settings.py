"""The settings of a diagnosis: levels of the tests, the decision rule's thresholds, the fits.

Defaults from ``diagnosis.decision`` and ``diagnosis.fit`` of the configuration
(:meth:`Settings.from_config`); the rule they set is described in :mod:`._rule`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._fit import PAPER_WF

__all__ = ["Settings"]


@dataclass(frozen=True)
class Settings:
    """Settings of a diagnosis (see the module docstring for the decision rule).

    Attributes
    ----------
    alpha : float
        Level of the smooth-pattern (systematic misfit) test.
    delta_bic : float
        A candidate's BIC must be at least this much below the baseline's (< 0).
    degree : int
        Highest Legendre degree of the smooth pattern per probe.
    model_error_um : float
        Accuracy of the simulated spaces (interpolation of the rays, µm), added in
        quadrature to the noise of each fitted point, so that data with almost no
        noise are not judged against an accuracy the spaces do not have.
    noise_um : float or None
        Noise sd of one measured deflection if known (µm); estimated otherwise.
    repeats : int
        Window focusing runs per fit (the best is polished).
    holdout : bool
        Cross-probe holdout when both probes are present.
    ambiguity_bic : float
        Eligible candidates whose BIC is within this of the chosen one's are reported
        as ``ambiguous_with`` (6: the "strong evidence" step of Kass and Raftery).
    seed : int
        Seed of the window focusing runs (>= 0).
    level : float
        Confidence level of the profile-likelihood intervals of every fit.
    intervals : {"chosen", "all", "cause"}
        Intervals of the baseline and of the chosen cause (or of the model a
        ``beyond_space`` verdict stands on), or of every candidate (about 1 s of
        CPU each on the default space), or of the chosen cause alone (a study's
        rows: X1d and X1h have the identification's intervals, and the
        baseline's, with a thickness nuisance, were a third of a ramp's CPU).
    window_focusing : dict
        N, Nb, C, max_iter.
    space_error : bool
        Weigh the scale-free space's correlated error along each curve (its rms per
        load p / X1d, measured against direct FE runs) in every chi^2 and in the
        misfit test, as the identification's intervals do; without it a smooth
        error of the space on soft skin (a few µm at the top of a 6 mm curve) reads
        as a systematic misfit.
    cause_window_decades : float or None
        Where the causes' rays are solved on demand (a probe or layers the
        precomputed space lacks), only the X1h/X1d nodes within this many decades
        of the neo-Hookean fit are solved (about 7 of 16 at 1.0), and the window
        widens by as much where a cause's fit reaches its outer cell; None: every
        node.  The precomputed rays are used whole.
    pattern_gate : bool
        True: a cause is named only where the smooth-pattern test of the neo-Hookean
        residuals fires first (step 1 of the rule).  False: a decisive candidate that
        removes the misfit is a detection of its own (its likelihood-ratio test of one
        extra parameter is the more powerful near the noise); the pattern test then
        only tells ``unexplained_misfit`` from ``neo_hookean_fits``.
    layer_test : bool
        On time curves of two apertures with creep named, test which layer creeps (a
        spectrum per layer against one for both; two fits more).
    time_causes : list of str or None
        The elastic causes a time-curve diagnosis tries beside creep (their rays
        beside the scale-free space); None: every one there.
    fe_correction : int
        Time curves: steps of the FE correction of each fit with creep (FE time
        solves at the fit remove the fast path's error,
        :func:`skinsuction.identify.fe_corrected_fit`); 0: the fast path alone.
    cause_rays_margin_bic : float or None
        Rays on demand: each cause is fitted first with its rays read off the
        geometry spaces whatever their error estimate, and fitted again with the
        rays over the tolerance solved only where that fit's delta BIC lies below
        this (the verdict moves only where a cause's BIC falls below the
        neo-Hookean one's; read rays with estimates up to 18 % moved it by at most
        0.01 in 28 causes of the layers study: ``docs/diagnosis.md``).  None: every
        such ray solved at once.
    """

    alpha: float = 0.01
    delta_bic: float = -10.0
    degree: int = 4
    model_error_um: float = 0.3
    noise_um: float | None = None
    repeats: int = 2
    holdout: bool = True
    ambiguity_bic: float = 6.0
    seed: int = 0
    level: float = 0.95
    intervals: str = "chosen"
    window_focusing: dict = field(default_factory=lambda: dict(PAPER_WF))
    space_error: bool = True
    cause_window_decades: float | None = 1.0
    pattern_gate: bool = False
    time_causes: tuple | None = None
    layer_test: bool = True
    fe_correction: int = 2
    cause_rays_margin_bic: float | None = 2.0

    def __post_init__(self):
        if not 0 < self.alpha < 1:
            raise ValueError(f"alpha must lie in (0, 1), got {self.alpha}")
        if not self.delta_bic < 0:
            raise ValueError(f"delta_bic must be negative, got {self.delta_bic}")
        if self.noise_um is not None and not self.noise_um > 0:
            raise ValueError(f"noise_um must be positive, got {self.noise_um}")
        if self.model_error_um < 0:
            raise ValueError("model_error_um must be >= 0")
        if int(self.seed) < 0:
            raise ValueError(f"seed must be >= 0, got {self.seed}")
        if self.intervals not in ("chosen", "all", "cause"):
            raise ValueError(f"intervals must be 'chosen', 'all' or 'cause', got "
                             f"{self.intervals!r}")
        if not 0.5 <= self.level < 1:
            raise ValueError(f"level must lie in [0.5, 1), got {self.level}")
        if not isinstance(self.pattern_gate, bool):
            raise ValueError(f"pattern_gate must be true or false, got {self.pattern_gate!r}")
        if self.time_causes is not None and (isinstance(self.time_causes, str) or not all(
                isinstance(c, str) for c in self.time_causes)):
            raise ValueError(f"time_causes must be a list of cause names or None, got "
                             f"{self.time_causes!r}")
        if int(self.fe_correction) != self.fe_correction or not 0 <= self.fe_correction <= 5:
            raise ValueError(f"fe_correction must be a whole number of steps in 0..5, got "
                             f"{self.fe_correction!r}")
        if self.cause_rays_margin_bic is not None and not self.cause_rays_margin_bic >= 0:
            raise ValueError("cause_rays_margin_bic must be >= 0 or None, got "
                             f"{self.cause_rays_margin_bic}")
        if self.cause_window_decades is not None and not self.cause_window_decades > 0:
            raise ValueError("cause_window_decades must be positive or None, got "
                             f"{self.cause_window_decades}")

    @classmethod
    def from_config(cls, decision: dict | None = None, fit: dict | None = None, **kw):
        """Settings from the configuration's ``diagnosis.decision`` and ``diagnosis.fit``.

        Parameters
        ----------
        decision : dict, optional
            Keys of the decision rule (``alpha``, ``delta_bic``, ``ambiguity_bic`` ...).
        fit : dict, optional
            Keys of the fits (``repeats``, ``holdout``, ``window_focusing`` ...); its
            ``window_focusing`` updates :data:`PAPER_WF`.
        **kw
            Any field, overriding both.

        Returns
        -------
        Settings
            Keys that are no field are left out.

        Examples
        --------
        >>> s = Settings.from_config({"alpha": 0.05}, {"window_focusing": {"n_samples": 500}})
        >>> s.alpha, s.window_focusing["n_samples"], s.window_focusing["n_best"]
        (0.05, 500, 20)
        """
        d = dict(decision or {})
        f = dict(fit or {})
        wf = {**PAPER_WF, **(f.pop("window_focusing", None) or {})}
        allowed = cls.__dataclass_fields__
        return cls(**{k: v for k, v in {**d, **f, **kw}.items() if k in allowed},
                   window_focusing=wf)
