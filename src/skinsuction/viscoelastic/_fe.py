"""The suction test in time: a stack of layers with a relaxation spectrum per layer.

Formulation (finite strain, internal variables; Simo 1987, Holzapfel 1996, in the
quasi-linear form of Fung): each layer's second Piola-Kirchhoff stress is its
long-time hyperelastic stress plus one over-stress per Prony term,

    S(t) = S_inf(C(t)) + sum_i Q_i(t),
    dQ_i/dt + Q_i / tau_i = g_i dS_br/dt,

where ``S_br`` is what a branch carries. ``branches="full"`` (the default): the
isochoric stress of the layer's law ``X1 (I1bar - 3) + X2 (I1bar - 3)^2`` as a
tensor (Simo's), and the penalty's Kirchhoff pressure ``pi = K (J - 1) J`` as a
scalar, whose stress ``pi C^-1`` stays hydrostatic in any configuration; every
branch keeps the model's nu = 0.49, so the instantaneous response is exactly the
elastic model at ``X1 (1 + sum g)``, and the scaling law ``M(s X1, s p)`` holds at
every rate. ``branches="isochoric"``: the isochoric tensor only (the bulk modulus
does not relax; the instantaneous Poisson ratio is lower). ``"whole_tensor"``: the
whole stress, penalty included, as one reference-configuration tensor; kept as a
warning: after a release the frozen penalty pressure is no longer hydrostatic, and
the response departs from linear theory by 14-16 % of Uf (docs/viscoelasticity.md).

Time discretisation (one implicit step ``t_n -> t_n+1 = t_n + dt``): ``S_br`` is
taken linear in time over the step, and the convolution is integrated exactly for
it,

    Q_i^n+1 = e_i Q_i^n + gamma_i (S_br(F^n+1) - S_br(F^n)),
    e_i = exp(-dt/tau_i),   gamma_i = g_i tau_i/dt (1 - e_i),

second order in dt, and exact in both limits (``gamma_i -> g_i`` as
``dt/tau_i -> 0``; ``-> 0`` as ``dt/tau_i -> inf``). Within a step the stress is
evaluated at the **fixed** history ``H = sum_i (e_i Q_i^n - gamma_i S_br^n)``:

    P = P_inf(F; X (1 + Gamma)) + F H + h F^-T,      Gamma = sum_i gamma_i,

the long-time law with scaled moduli (the branch law is linear in its
coefficients) plus the history's ``F H`` and ``h F^-T`` (h: the scalar history of
the pressure), whose tangents are ``delta_ik H_LJ`` and ``-h F^-T_iL F^-T_kJ``. (The
issue found FElupe's ``finite_strain_viscoelastic`` first order because it
differentiates an energy through the internal variable; here no energy is
differentiated.)

Everything elastic is :class:`skinsuction.model.SuctionTest`'s (mesh, boundary
conditions, probe wall, suction, penalty at nu = 0.49, fast assembly): with g = 0
this model is that one.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..model import MeshSettings, ParameterError, SuctionTest
from ..model import SWAP, FastAssembly, NoEquilibrium, material_response

BRANCHES = ("full", "isochoric", "whole_tensor")


def second_piola(f, P):
    """``S = F^-1 P`` in the 5-component axisymmetric form (zz, zr, rz, rr, hoop)."""
    a, b, c, d, h = f
    det2 = a * d - b * c
    Pzz, Pzr, Prz, Prr, Phh = P
    return np.stack([(d * Pzz - b * Prz) / det2, (d * Pzr - b * Prr) / det2,
                     (a * Prz - c * Pzz) / det2, (a * Prr - c * Pzr) / det2, Phh / h])


def first_piola(f, S):
    """``P = F S`` in the 5-component axisymmetric form (zz, zr, rz, rr, hoop).

    Examples
    --------
    >>> f = np.array([[1.1], [0.2], [-0.1], [0.9], [1.05]])
    >>> S = np.array([[0.3], [0.1], [0.1], [-0.2], [0.05]])
    >>> bool(np.allclose(second_piola(f, first_piola(f, S)), S))
    True
    """
    a, b, c, d, h = f
    Szz, Szr, Srz, Srr, Shh = S
    return np.stack([a * Szz + b * Srz, a * Szr + b * Srr, c * Szz + d * Srz,
                     c * Szr + d * Srr, h * Shh])


def _inverse_transpose(f):
    """``F^-T`` (5, n) and ``d(F^-T)/dF`` (n, 5, 5) in the 5-component order."""
    a, b, c, d, h = f
    det2 = a * d - b * c
    ift = np.stack([d / det2, -c / det2, -b / det2, a / det2, 1.0 / h])
    ext = np.concatenate([ift, np.zeros((1,) + ift.shape[1:])])
    swap = (ext[:, None] * ext[None, :]).reshape(36, -1)[SWAP]  # iFT_iL iFT_kJ
    return ift, -swap.transpose(2, 0, 1)


def _history_tangent(H):
    """d(F H)/dF at fixed H: ``delta_ik H_LJ``, (n, 5, 5) in the 5-component order."""
    Hzz, Hzr, Hrz, Hrr, Hhh = H
    A = np.zeros((H.shape[1], 5, 5))
    for block in (0, 2):  # rows F_z., then F_r.: the same 2x2 block of H
        A[:, block, block], A[:, block, block + 1] = Hzz, Hrz
        A[:, block + 1, block], A[:, block + 1, block + 1] = Hzr, Hrr
    A[:, 4, 4] = Hhh
    return A


class ViscousAssembly(FastAssembly):
    """The fast assembly of :mod:`skinsuction.model._fast` with over-stress branches.

    Built from an elastic :class:`FastAssembly` (same mesh, loads, wall, sparsity
    and ordering). Per time step: :meth:`begin_step` fixes the history and the
    scaled moduli for a step ``dt``; :meth:`residual` and :meth:`tangent` are then
    those of the step's algorithmic stress; :meth:`commit` updates the internal
    variables at the converged state.

    Parameters
    ----------
    g, tau_s : ndarray, shape (branches, Gauss points)
        Fraction and relaxation time of each branch at each Gauss point (cell by
        cell, as the assembly's points; g = 0 where a layer has fewer terms).
    branches : {"full", "isochoric"}
        Which part of the layer's law the branches carry (see the module).
    """

    @classmethod
    def from_elastic(cls, fast, g, tau_s, branches="full"):
        obj = cls.__new__(cls)
        obj.__dict__.update(fast.__dict__)
        obj.base = (fast.x1.copy(), fast.x2.copy(), fast.bulk.copy())
        obj.g = np.asarray(g, float).reshape(-1, fast.x1.size)
        obj.tau = np.asarray(tau_s, float).reshape(-1, fast.x1.size)
        if branches not in BRANCHES:
            raise ParameterError(f"branches must be one of {BRANCHES}, not {branches!r}")
        obj.branches = branches
        # branches with g = 0 everywhere do nothing: drop them
        live = np.any(obj.g > 0, axis=1)
        obj.g, obj.tau = obj.g[live], obj.tau[live]
        obj.H, obj.h_vol = None, None
        zero = np.zeros(fast.ndof)
        # the branch stresses at rest (the pre-stress, if any), taken as relaxed
        obj.S_br, obj.pi_br = obj._branch_stress(obj._components(zero))
        obj.Q = np.zeros((len(obj.g),) + obj.S_br.shape)
        obj.q = np.zeros((len(obj.g),) + obj.pi_br.shape)
        obj._step = None
        return obj

    @property
    def viscous(self):
        return len(self.g) > 0

    def _branch_stress(self, f):
        """The stresses a branch of unit fraction relaxes, in the mesh's configuration:
        the tensor ``S_br`` (isochoric part; the whole law for ``"whole_tensor"``) and
        the scalar Kirchhoff pressure ``pi`` of the penalty (``"full"``; else 0),
        whose stress ``pi C^-1`` stays hydrostatic in any configuration."""
        x1, x2, bulk = self.base
        zero = np.zeros_like(bulk)
        with np.errstate(invalid="ignore", divide="ignore"):
            P, _ = material_response(f, x1, x2, bulk if self.branches == "whole_tensor" else zero,
                             self.f0, tangent=False)
            S = second_piola(f, P)
            if self.branches != "full":
                return S, np.zeros(f.shape[1])
            Pv, _ = material_response(f, zero, zero, bulk, self.f0, tangent=False)
            return S, Pv[4] * f[4]  # P_vol = pi F^-T: its hoop component is pi / F_hoop

    def begin_step(self, dt):
        """Fix the history and the scaled moduli of a step of ``dt`` seconds."""
        if not self.viscous:
            self.H = None
            return
        x = dt / self.tau
        e = np.exp(-x)
        gamma = self.g * (-np.expm1(-x) / x)  # g tau/dt (1 - e), exact as x -> 0
        Gamma = gamma.sum(axis=0)
        x1, x2, bulk = self.base
        self.x1, self.x2 = x1 * (1.0 + Gamma), x2 * (1.0 + Gamma)
        self.bulk = bulk if self.branches == "isochoric" else bulk * (1.0 + Gamma)
        self.H = np.einsum("bn,bpn->pn", e, self.Q) - Gamma * self.S_br
        self.h_vol = np.einsum("bn,bn->n", e, self.q) - Gamma * self.pi_br
        self._step = (e, gamma)

    def commit(self, u):
        """Update the internal variables at the converged displacements ``u``."""
        if not self.viscous:
            return
        e, gamma = self._step
        S, pi = self._branch_stress(self._components(u))
        self.Q = e[:, None] * self.Q + gamma[:, None] * (S - self.S_br)
        self.q = e * self.q + gamma * (pi - self.pi_br)
        self.S_br, self.pi_br = S, pi

    def _added_stress(self, f, tangent):
        """``F H + h_vol F^-T`` at the fixed history, and its tangent: added to the
        elastic law's stress in the one pass of the fast assembly."""
        if self.H is None:
            return None
        ift, dift = _inverse_transpose(f)
        P = first_piola(f, self.H) + self.h_vol * ift
        if not tangent:
            return P, None
        return P, _history_tangent(self.H) + self.h_vol[:, None, None] * dift


@dataclass(frozen=True)
class History:
    """Apex deflection of one suction test in time, as far as the solver got.

    Attributes
    ----------
    times_s, pressure_mbar : ndarray
        The requested history (piecewise linear between these points).
    deflection_mm : ndarray
        Apex deflection at each time (mm, positive into the probe); NaN after a stop.
    converged : bool
        True if every time was reached.
    reason : str
        Empty if converged, otherwise why the solver stopped.
    newton_iterations, steps : int
        Newton iterations (cut-back steps included) and accepted time steps.
    dofs : int
    seconds : float
        Wall time (model set-up included).
    info : dict
        Parameters and settings, for provenance.
    """

    times_s: np.ndarray
    pressure_mbar: np.ndarray
    deflection_mm: np.ndarray
    converged: bool
    reason: str = ""
    newton_iterations: int = 0
    steps: int = 0
    dofs: int = 0
    seconds: float = 0.0
    info: dict = field(default_factory=dict)


class ViscoelasticSuctionTest:
    """The suction-test model of a stack of layers with a relaxation spectrum per
    layer, solved in time (see the module for the formulation).

    Parameters
    ----------
    skin : Skin
        The layers, each with its long-time (equilibrium) moduli X1, X2 and its
        relaxation spectrum (``Layer.spectrum``; X2 relaxes with X1), and the
        bottom. A pre-stretch is taken as relaxed at t = 0 (held for long before
        the test).
    probe : Probe or float
        The probe, or its aperture diameter in mm.
    mesh : MeshSettings or dict, optional
        As :class:`skinsuction.model.SuctionTest` (the fast engine only).
    branches : {"full", "isochoric", "whole_tensor"}
        What the branches carry: the isochoric tensor and the penalty's pressure as
        a scalar (default; nu = 0.49 at every rate), the isochoric part only (the
        bulk modulus does not relax), or the whole stress as one tensor (a warning,
        see the module).
    """

    def __init__(self, skin, probe=6.0, mesh=None, branches="full"):
        settings = mesh.to_dict() if isinstance(mesh, MeshSettings) else dict(mesh or {})
        if settings.get("engine", "auto") == "felupe":
            raise ParameterError("the viscoelastic model runs on the fast engine only")
        self.model = SuctionTest(skin, probe, {**settings, "engine": "fast"})
        self.spectra = {layer.name: layer.spectrum for layer in skin.layers}
        fast = self.model.fast
        # the layer of each Gauss point (the mesh has a node line on every interface)
        layer = np.repeat(self.model.layer, fast.nq)
        nb = max(spectrum.terms for spectrum in self.spectra.values())
        g = np.zeros((nb, layer.size))
        tau = np.ones((nb, layer.size))
        for index, spectrum in enumerate(self.spectra.values()):
            mask = layer == index
            for k in range(spectrum.terms):
                g[k, mask], tau[k, mask] = spectrum.g[k], spectrum.tau_s[k]
        self.assembly = ViscousAssembly.from_elastic(fast, g, tau, branches)
        self.model.fast = self.assembly  # the model's Newton pieces now assemble it
        self.parameters = dict(
            self.model.parameters, branches=branches,
            prony={k: {"g": list(v.g), "tau_s": list(v.tau_s)} for k, v in self.spectra.items()},
        )

    @property
    def dofs(self):
        return self.model.dofs

    def _predict(self, u_now, u_before, dt, h_last):
        """Set the step's start: the extrapolation in time, unless the last
        equilibrium has the smaller residual (after a switch of the load); returns
        the residual there."""
        m = self.model
        u = m.field[0].values
        with np.errstate(all="ignore"):
            u[:] = u_now
            f = m._residual()
            if h_last > 0:
                u[:] = u_now + (dt / h_last) * (u_now - u_before)
                f_pred = m._residual()
                if (np.all(np.isfinite(f_pred))
                        and np.linalg.norm(f_pred[m.dof1]) < np.linalg.norm(f[m.dof1])):
                    return f_pred
                u[:] = u_now
        return f

    def run(self, times_s, pressures_mbar, max_step_s=None, tol=1e-6, maxiter=25,
            min_step_fraction=1e-4, iteration_budget=None, progress=None):
        """Solve the pressure history ``p(t)``, piecewise linear between the given
        points, by implicit time steps.

        Each interval between two given times is one step (or ``ceil(dt /
        max_step_s)`` equal steps); a step that fails is cut back by 4 (down to
        ``min_step_fraction`` of the interval). Never raises on non-convergence:
        the history ends at the last time reached, and ``reason`` says why.

        Parameters
        ----------
        times_s : array_like
            Strictly increasing times (s); the skin is at rest and relaxed at the
            first one.
        pressures_mbar : array_like
            Suction at each time (mbar, >= 0), starting at 0.
        max_step_s : float, optional
            Largest time step.
        tol : float
            Norm of the free residual relative to the reactions (floored at 1e-3
            of the largest reactions so far).

        Returns
        -------
        History
        """
        start = time.perf_counter()
        t, p = _history_arrays(times_s, pressures_mbar)
        if iteration_budget is None:
            iteration_budget = 40 * len(t)
        m, asm = self.model, self.assembly
        deflection = np.full(t.shape, np.nan)
        deflection[0] = 0.0
        u = m.field[0].values
        u_now, u_before = u.copy(), u.copy()
        t_now, h_last = t[0], 0.0
        iterations, steps, reason, lu, peak = 0, 0, "", None, 0.0
        for k in range(1, len(t)):
            span = t[k] - t[k - 1]
            nominal = span if max_step_s is None else span / math.ceil(span / max_step_s - 1e-9)
            h = nominal
            rate = (p[k] - p[k - 1]) / span
            while t_now < t[k] - 1e-9 * span:
                if iterations > iteration_budget:
                    reason = f"iteration budget of {iteration_budget} spent at t = {t_now:g} s"
                    break
                remaining = t[k] - t_now
                clipped = remaining <= h * (1 + 1e-9)
                dt = remaining if clipped else h
                t_next = t[k] if clipped else t_now + dt
                p_next = p[k] if clipped else p[k - 1] + rate * (t_next - t[k - 1])
                asm.begin_step(dt)
                m._set_pressure(p_next)
                f = self._predict(u_now, u_before, dt, h_last)
                try:
                    # the tangent goes on to the next step even after a hard one: its
                    # last is of this step's end, and Newton drops it if it does not
                    # contract (2.0 -> 1.15 CPU-s for a mode-1 solve of the 2 mm probe)
                    with np.errstate(all="ignore"):
                        lu, used, f = self.model.newton(lu, tol, maxiter, f, 1e-3 * peak,
                                                        keep_fresh=True)
                    iterations += used
                except (NoEquilibrium, RuntimeError, ValueError, np.linalg.LinAlgError) as err:
                    iterations += getattr(err, "iterations", maxiter)
                    u[:] = u_now
                    lu, h = None, dt / 4
                    if h < min_step_fraction * span:
                        reason = (f"no equilibrium after t = {t_now:g} s, p = {p_next:g} mbar "
                                  f"(time step cut back below {min_step_fraction:g} of the "
                                  f"interval: {err})")
                        break
                    continue
                asm.commit(u)
                m._commit()
                steps += 1
                peak = max(peak, float(np.linalg.norm(f[m.dof0])))
                u_before, u_now = u_now, u.copy()
                t_now, h_last = t_next, dt
                if not clipped:
                    h = min(2 * h, nominal)
            if reason:
                break
            deflection[k] = m.apex_deflection()
            if progress is not None:
                progress(k, len(t) - 1, float(t[k]))
        u[:] = u_now
        return History(
            times_s=t, pressure_mbar=p, deflection_mm=deflection, converged=not reason,
            reason=reason, newton_iterations=iterations, steps=steps, dofs=self.dofs,
            seconds=time.perf_counter() - start,
            info=dict(self.parameters, mesh=m.settings.to_dict(), engine="fast+viscous"),
        )


def _history_arrays(times_s, pressures_mbar):
    t = np.asarray(times_s, dtype=float)
    p = np.asarray(pressures_mbar, dtype=float)
    if t.ndim != 1 or t.shape != p.shape or len(t) < 2:
        raise ParameterError("times_s and pressures_mbar: two 1-D arrays of the same length >= 2")
    if np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise ParameterError("times_s must increase strictly")
    if p[0] != 0 or np.any(p < 0) or not np.all(np.isfinite(p)):
        raise ParameterError("pressures_mbar must start at 0 and be finite and >= 0")
    return t, p


def simulate_history(skin, times_s, pressures_mbar, probe=6.0, mesh=None, branches="full",
                     max_step_s=None, tol=1e-6, iteration_budget=None, progress=None):
    """Apex deflection against time of a skin whose layers carry relaxation spectra.

    The elastic model of :func:`skinsuction.model.simulate` (X1 the long-time
    moduli) with each layer's Prony series (instantaneous moduli ``X1 (1 + sum
    g)``), under the suction ``p(t)`` piecewise linear between the given points,
    by implicit time steps at those times (finer with ``max_step_s``).

    Parameters
    ----------
    skin : Skin
        The layers, with their spectra (``Skin.two_layer(x1d, x1h, spectrum=...)``
        shares one spectrum or takes one per layer).
    times_s, pressures_mbar : array_like
        The history: times (s, increasing) and suction (mbar, from 0). See
        :func:`skinsuction.viscoelastic.mode1_history` and ``mode2_history``.
    probe : Probe or float
        The probe, or its aperture diameter in mm.
    mesh : dict or MeshSettings, optional
        As :func:`skinsuction.model.simulate`.
    branches : {"full", "isochoric", "whole_tensor"}
        What the branches relax (see :class:`ViscoelasticSuctionTest`).
    max_step_s : float, optional
        Largest time step (default: the given intervals).

    Returns
    -------
    History

    Examples
    --------
    A step-like rise to 40 mbar held for 1 s, relaxation time 0.2 s, coarse mesh:
    the skin jumps to the instantaneous response and creeps towards the long-time
    one (``X1 (1 + g)`` = 2 ``X1`` here: about half the long-time deflection).

    >>> from skinsuction.model import Prony, Skin
    >>> skin = Skin.two_layer(0.08, 4.1e-3, spectrum=Prony([1.0], [0.2]))
    >>> h = simulate_history(skin, [0, 0.001, 0.2, 1.0, 3.0], [0, 40, 40, 40, 40],
    ...                      mesh={"refinement": 0.5}, max_step_s=0.05)
    >>> h.converged, [round(float(v / h.deflection_mm[-1]), 2) for v in h.deflection_mm[1:]]
    (True, [0.5, 0.69, 0.96, 1.0])
    """
    model = ViscoelasticSuctionTest(skin, probe, mesh, branches)
    return model.run(times_s, pressures_mbar, max_step_s=max_step_s, tol=tol,
                     iteration_budget=iteration_budget, progress=progress)
