"""The forward problem: apex deflection of the skin under a suction probe."""

import time

import felupe as fem
import numpy as np
from scipy.sparse.linalg import splu

from ._curve import Curve, ParameterError
from ._fast import _SUPERLU_OPTIONS, FastAssembly, OrderedFactors, surface_edges
from ._geometry import MeshSettings, suction_mesh
from ._material import SkinLayers, bulk_modulus, thickness_stretch
from ._probe import ProbeEdge
from ._skin import BOTTOM_CONDITIONS, Probe, Ramp, Skin

MBAR_TO_MPA = 1e-4
DEFAULT_PRESSURES_MBAR = np.arange(0.0, 101.0, 2.0)


def _factorize(K):
    # MMD on A^T+A in symmetric mode: the tangent is symmetric in pattern and in
    # value. SuperLU's default threshold (1.0) still swaps rows for any larger
    # off-diagonal entry, which wrecks the symmetric ordering (3-4x the fill); the
    # tangent of a stable equilibrium is positive definite, so diagonal pivots are
    # kept unless one is below a tenth of its column's largest entry
    return splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", options=_SUPERLU_OPTIONS)


class TangentFactorizer:
    """Factorises the tangents of one model, computing the fill-reducing order once.

    SuperLU orders the matrix anew at every factorisation; for these tangents
    (2-3 k DOFs) the minimum-degree ordering is about a sixth of it (8.4 -> 7.2 ms
    on a 2 670-DOF ray tangent). The sparsity pattern of a model's tangent hardly
    changes (the tangent at rest lacks a few entries), so the order SuperLU found
    is kept and each later tangent is permuted symmetrically into it and
    factorised in its natural order: the same fill and pivots. Any symmetric
    permutation is a valid order, so a changed pattern costs fill, never
    correctness; the order is recomputed when the number of entries changes.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> K = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(6, 6)).tocsr()
    >>> factorize = TangentFactorizer(np.arange(6))
    >>> b = np.ones(6)
    >>> x1, x2 = factorize(K).solve(b), factorize(K).solve(b)  # ordered, then reused
    >>> bool(np.allclose(K @ x1, b) and np.allclose(K @ x2, b))
    True
    """

    def __init__(self, free_dofs):
        self.free = np.asarray(free_dofs)
        self._rows = None  # free DOFs in the kept order
        self._nnz = -1

    def __call__(self, K):
        K = K.tocsr()
        if self._rows is not None:
            A = K[self._rows][:, self._rows]
            if A.nnz == self._nnz:
                lu = splu(A.tocsc(), permc_spec="NATURAL", options=_SUPERLU_OPTIONS)
                return OrderedFactors(lu, self._order)
        A = K[self.free][:, self.free]  # in the model's own order: SuperLU orders it anew
        lu = _factorize(A)
        self._order = np.argsort(lu.perm_c)
        self._rows, self._nnz = self.free[self._order], A.nnz
        return lu


class NoEquilibrium(RuntimeError):
    """Newton's method found no equilibrium for one pressure increment."""

    def __init__(self, message, iterations=0):
        super().__init__(message)
        self.iterations = iterations


def _probe_mm(probe):
    return (probe if isinstance(probe, Probe) else Probe(probe)).aperture_mm


def _mesh_settings(mesh, engine=None):
    if not isinstance(mesh, MeshSettings):
        mesh = MeshSettings.from_dict(mesh)
    if engine is not None:
        mesh = MeshSettings.from_dict({**mesh.to_dict(), "engine": engine})
    if mesh.engine not in ("auto", "fast", "felupe"):
        raise ParameterError(f"engine must be 'auto', 'fast' or 'felupe', not {mesh.engine!r}")
    if mesh.engine == "fast" and not _fast_applies(mesh):
        raise ParameterError(
            "the fast engine assembles the displacement formulation with a sharp "
            "probe edge only: use engine 'felupe' for formulation 'mixed' or "
            "edge_radius > 0"
        )
    return mesh


def _fast_applies(mesh):
    return mesh.formulation == "displacement" and mesh.edge_radius == 0


def layer_prestretch(skin, poisson=0.49):
    """Per layer, the diagonal ``(axial, radial, hoop)`` of the pre-deformation F0:
    the in-plane pre-stretch, and the through-thickness stretch that keeps the
    layer's surface traction-free (each layer contracts by its own law).

    Parameters
    ----------
    skin : Skin
    poisson : float

    Returns
    -------
    ndarray, shape (layers, 3)

    Examples
    --------
    >>> layer_prestretch(Skin.two_layer(0.08, 4e-4)).tolist()
    [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]
    """
    return np.array([
        [thickness_stretch(layer.prestretch, layer.X1, layer.X2, poisson),
         layer.prestretch, layer.prestretch]
        for layer in skin.layers
    ])


class SuctionTest:
    """The axisymmetric suction-test model of a stack of skin layers, assembled
    once and solved for a sequence of pressures.

    Parameters
    ----------
    skin : Skin
        The layers (top first: thickness, X1, X2 of ``W = X1 (I1 - 3) + X2 (I1 -
        3)^2`` with isochoric I1, pre-stretch) and the bottom condition. The
        layers' spectra are the viscoelastic model's
        (:class:`skinsuction.viscoelastic.ViscoelasticSuctionTest`); here the
        long-time moduli act.
    probe : Probe or float
        The probe, or its aperture diameter in mm.
    mesh : MeshSettings or dict or None
        Discretisation settings.
    poisson : float
        Small-strain Poisson ratio that sets the volumetric penalty.

    Examples
    --------
    >>> model = SuctionTest(Skin.two_layer(0.08, 4.1e-4), 2.0, {"refinement": 0.5})
    >>> model.layer_names, int(model.layer.max())
    (('dermis', 'hypodermis'), 1)
    """

    def __init__(self, skin, probe=6.0, mesh=None, poisson=0.49):
        if not isinstance(skin, Skin):
            raise ParameterError(
                f"the model takes a Skin (e.g. Skin.two_layer(x1d, x1h)), not {skin!r}")
        probe_mm = _probe_mm(probe)
        mesh = _mesh_settings(mesh)
        fast_applies = _fast_applies(mesh)
        self.skin = skin
        self.layer_names = skin.names
        self.settings = mesh
        self.parameters = dict(skin=skin.to_dict(), probe_mm=probe_mm, bottom=skin.bottom,
                               poisson=poisson)
        try:  # the two-layer records keep the keys they always had
            self.parameters.update(skin.two_layer_values())
        except ParameterError:
            pass
        bottom = skin.bottom
        depth = skin.depth
        self.mesh, self.layer = suction_mesh(probe_mm, skin.thicknesses, mesh)
        a = probe_mm / 2
        # the skin is glued to the probe's face outside the rounded edge
        a_glued = a * (1 + mesh.edge_radius)
        if mesh.probe_wall:
            # reference point of the rigid probe, outside every cell; it lies on
            # the glued face, so it is fixed with it
            self.mesh.update(points=np.vstack([self.mesh.points, [0.0, a_glued]]))
        z, r = self.mesh.points.T
        tol = 1e-9 * (a + depth)

        quadrature = fem.GaussLegendre(order=2 if mesh.quadrature == "full" else 1, dim=2)
        if mesh.element == "quad9":
            region = fem.RegionBiQuadraticQuad(self.mesh, quadrature=quadrature)
            Boundary = fem.RegionBiQuadraticQuadBoundary
        else:
            region = fem.RegionQuadraticQuad(self.mesh, quadrature=quadrature)
            Boundary = fem.RegionQuadraticQuadBoundary
        self.field = fem.FieldContainer([fem.FieldAxisymmetric(region, dim=2)])

        x1 = np.array([layer.X1 for layer in skin.layers])[self.layer]
        x2 = np.array([layer.X2 for layer in skin.layers])[self.layer]
        F0 = None
        if skin.has_prestretch:
            if mesh.formulation == "mixed":
                raise ParameterError("prestretch needs the displacement formulation")
            # the mesh is the pre-stretched skin (thicknesses as measured in vivo);
            # each layer contracts through its thickness so the surface is free
            F0 = layer_prestretch(skin, poisson)[self.layer].T
        if mesh.formulation == "mixed":
            # cell-wise constant pressure and volume ratio (condensed): the volumetric
            # penalty acts on the mean dilatation of a cell, which avoids locking
            # without reduced integration and its spurious modes
            umat = SkinLayers(x1=x1, x2=x2, bulk=0.0)
            self.solid = fem.SolidBodyNearlyIncompressible(
                umat, self.field, bulk=bulk_modulus(x1, poisson)
            )
        else:
            umat = SkinLayers(x1=x1, x2=x2, bulk=bulk_modulus(x1, poisson), prestretch=F0)
            self.solid = fem.SolidBody(umat, self.field)

        inside = np.isclose(z, 0, atol=tol) & (r <= a_glued + tol)
        surface = Boundary(self.mesh, only_surface=True, mask=inside, ensure_3d=True)
        self.suction = fem.SolidBodyPressure(
            fem.FieldContainer([fem.FieldAxisymmetric(surface, dim=2)])
        )

        self.items = [self.solid, self.suction]
        if mesh.probe_wall:
            # the skin inside the aperture cannot enter the probe: a frictionless
            # rigid wall at r = a (penalty contact), inactive until a surface point
            # is pulled outwards past the aperture edge
            free_top = np.flatnonzero(inside & (r < a_glued - tol))
            if mesh.edge_radius > 0:
                wall = ProbeEdge(
                    self.field, points=free_top, centerpoint=len(z) - 1,
                    edge_radius=mesh.edge_radius * a,
                    multiplier=mesh.wall_penalty, items=[self.solid],
                )
            else:
                wall = fem.ContactRigidPlane(
                    self.field, points=free_top, centerpoint=len(z) - 1,
                    normal=[0.0, -1.0], multiplier=mesh.wall_penalty,
                    items=[self.solid],
                )
            self.items.append(wall)
        u = self.field[0]
        boundaries = {
            "axis": fem.Boundary(u, mask=np.isclose(r, 0, atol=tol), skip=(1, 0)),
            "glued": fem.Boundary(
                u, mask=np.isclose(z, 0, atol=tol) & (r >= a_glued - tol)
            ),
        }
        bottom_nodes = np.isclose(z, -depth, atol=tol)
        if bottom == "fixed":
            boundaries["bottom"] = fem.Boundary(u, mask=bottom_nodes)
        elif bottom == "axial":
            boundaries["bottom"] = fem.Boundary(u, mask=bottom_nodes, skip=(0, 1))
        if skin.has_prestretch:
            # the skin beyond the model holds the in-plane tension
            boundaries["outer"] = fem.Boundary(
                u, mask=np.isclose(r, r.max(), atol=tol), skip=(1, 0)
            )
        self.boundaries = boundaries
        self.dof0, self.dof1 = fem.dof.partition(self.field, boundaries)
        self.ext0 = fem.dof.apply(self.field, boundaries, self.dof0)
        self.apex = int(np.flatnonzero(np.isclose(z, 0, atol=tol) & np.isclose(r, 0, atol=tol))[0])
        self.dofs = self.field[0].values.size
        self.engine = mesh.engine
        if self.engine == "auto":
            self.engine = "fast" if fast_applies else "felupe"
        self._pressure = 0.0  # FElupe's sign: suction is negative
        self._wall = self.items[2] if mesh.probe_wall else None
        if self.engine == "fast":
            self.fast = FastAssembly(
                region, umat.x1, umat.x2, umat.bulk,
                None if F0 is None else np.asarray(F0),
                surface_edges(self.mesh.cells, self.mesh.points, inside),
                [] if self._wall is None else self._wall.points, a_glued,
                self.dof1, self.mesh.npoints,
                wall_center=None if self._wall is None else self._wall.centerpoint,
            )
            # the wall's penalty follows FElupe's: re-evaluated from the solid's
            # last tangent at the first evaluation of each increment
            self._wall_stale = True
        else:
            self._factorize = TangentFactorizer(self.dof1)

    def apex_deflection(self):
        """Current apex deflection (mm, positive into the probe)."""
        return float(self.field[0].values[self.apex, 0])

    def largest_stretch(self):
        """Largest principal stretch over the Gauss points, and where (z, r in mm)."""
        F = self.field.extract()[0]
        C = np.einsum("kIqc,kJqc->qcIJ", F, F)
        stretch = np.sqrt(np.linalg.eigvalsh(C)[..., -1])
        q, c = np.unravel_index(np.argmax(stretch), stretch.shape)
        centre = self.mesh.points[self.mesh.cells[c, :4]].mean(axis=0)
        return float(stretch[q, c]), centre

    def distortion_note(self, pressures, deflection):
        """Evidence for why a run stopped: the largest stretch of the last
        equilibrium and whether M(p) was still straight (no limit point)."""
        stretch, (z, r) = self.largest_stretch()
        note = f"largest principal stretch {stretch:.2f} at z = {z:.3f}, r = {r:.3f} mm"
        ok = np.flatnonzero(np.isfinite(deflection))
        if len(ok) >= 4:
            slope = np.diff(deflection[ok]) / np.diff(pressures[ok])
            note += (
                f"; dM/dp at the last equilibrium is {slope[-1] / slope[0]:.2f}x the "
                "initial one"
            )
        return note

    def _set_pressure(self, pressure_mbar):
        # suction is a negative pressure: FElupe's positive pressure pushes inwards
        self._pressure = -pressure_mbar * MBAR_TO_MPA
        if self.engine == "felupe":
            self.suction.update(self._pressure)

    def _residual(self):
        if self.engine == "felupe":
            return fem.tools.fun(self.items, self.field)
        u = self.field[0].values
        if self._wall is not None and self._wall_stale:
            if self.fast.solid_diagonal is None:
                self.fast.tangent(u, self._pressure)  # the solid's stiffness, once
            self.fast.update_wall_multiplier(self.settings.wall_penalty)
            self._wall_stale = False
        return self.fast.residual(u, self._pressure)

    def _tangent(self):
        if self.engine == "felupe":
            return self._factorize(fem.tools.jac(self.items, self.field))
        return self.fast.factorize(self.fast.tangent(self.field[0].values, self._pressure))

    def _commit(self):
        """Accept the current state as the increment's equilibrium."""
        if self.engine == "felupe":
            for item in self.items:
                item.results.update_statevars()
        else:
            self._wall_stale = True

    def _equilibrium(self, pressure_mbar, lu, tol, maxiter, xtol=1e-9, f=None,
                     stall_after=8, stall_window=4):
        """Newton iterations at one pressure, in place on the displacement field
        (:meth:`newton`). ``f`` is the residual of the current state at this
        pressure, if known. Returns the tangent in use and the number of iterations.
        """
        self._set_pressure(pressure_mbar)
        if f is None:
            f = self._residual()
        lu, iterations, _ = self.newton(lu, tol, maxiter, f, 0.0, xtol, stall_after,
                                        stall_window)
        return lu, iterations

    def newton(self, lu, tol, maxiter, f, floor=0.0, xtol=1e-9, stall_after=8,
               stall_window=4):
        """Newton's method at the current load, in place on the displacement field.

        The factorised tangent ``lu`` (of an earlier increment, if given) serves
        while it cuts the residual tenfold an iteration; otherwise, and from the
        third iteration on, the tangent is refactorised (full Newton). A step
        that inverts an element (non-finite residual) is halved before it is
        accepted. An increment whose residual has not halved in ``stall_window``
        iterations, after ``stall_after``, is given up (the caller cuts it back).

        Parameters
        ----------
        lu : factors or None
            A tangent to start with.
        tol : float
            Residual of the free DOFs relative to the reactions (floored by
            ``floor``: a time step after a release, where both vanish).
        maxiter : int
            Iterations before :class:`NoEquilibrium` is raised.
        f : ndarray
            The residual of the current state.
        floor : float
            Smallest reaction norm the criterion divides by.
        xtol : float
            A correction below ``xtol`` of the displacement also ends it.
        stall_after, stall_window : int
            The stall rule above.

        Returns
        -------
        (factors, int, ndarray)
            The tangent in use, the iterations spent and the final residual.
        """
        u = self.field[0].values.reshape(-1)
        history = []  # residual norms of this increment's iterations
        for iteration in range(1, maxiter + 1):
            if not np.all(np.isfinite(f)):
                raise NoEquilibrium("an element is inverted", iteration - 1)
            r1 = f[self.dof1]
            norm_r1 = np.linalg.norm(r1)
            if norm_r1 <= tol * max(np.linalg.norm(f[self.dof0]), floor):
                return lu, iteration - 1, f
            history.append(norm_r1)
            # full Newton from the 3rd iteration on contracts a sound increment
            # quadratically; one that has not halved its residual in 4 of them
            # wanders (a limit point, an element about to invert): a smaller
            # increment is cheaper than the rest of maxiter
            if iteration > stall_after and norm_r1 > 0.5 * min(history[:-stall_window]):
                raise NoEquilibrium(
                    f"no contraction in {stall_window} iterations", iteration - 1
                )
            # an earlier tangent serves while it contracts the residual tenfold: a
            # factorisation costs six modified iterations on the fast path, and a
            # tangent that contracts less wastes more than it saves (measured:
            # 1.7x less CPU over 28 rays than reuse while halving, to the 5th
            # iteration)
            if lu is None or iteration > 2 or (iteration > 1 and norm_r1 > 0.1 * history[-2]):
                lu = self._tangent()
            du = lu.solve(-r1)
            u_start = u[self.dof1].copy()
            for _ in range(6):
                u[self.dof1] = u_start + du
                f = self._residual()
                if np.all(np.isfinite(f)):
                    break
                du *= 0.5
            # when the loads are tiny against the moduli, the residual stalls at its
            # round-off floor first: then a negligible correction means converged
            if np.all(np.isfinite(f)) and np.linalg.norm(du) <= xtol * np.linalg.norm(u_start + du):
                return lu, iteration, f
        raise NoEquilibrium(f"no convergence in {maxiter} iterations", maxiter)

    def run(
        self,
        pressures_mbar=None,
        tol=1e-6,
        maxiter=25,
        min_increment_mbar=0.01,
        iteration_budget=None,
        progress=None,
        stall_after=8,
    ):
        """Solve for each pressure, with an extrapolated predictor and cutback.

        Never raises on non-convergence: the curve ends at the last converged
        pressure, and ``reason`` says why.

        Parameters
        ----------
        pressures_mbar : array_like, optional
            Pressures from 0, ascending (default 0, 2, ..., 100 mbar).
        tol : float
            Norm of the residual of the free DOFs relative to the reactions.
        maxiter : int
            Newton iterations per increment before it is cut back.
        min_increment_mbar : float
            Smallest increment tried before giving up.
        iteration_budget : int, optional
            Total Newton iterations before giving up (default 20 per pressure step),
            so that a hopeless point costs a bounded time.
        progress : callable, optional
            Called as ``progress(k, n, pressure_mbar)`` after the k-th of the n
            pressures after 0 is reached (e.g. :class:`skinsuction.Progress`'s bar).
        stall_after : int
            Newton iterations of an increment before one whose residual has not
            halved in 4 is given up and cut back (8; more is slower but can carry
            a soft corner further, see ``config.yaml``'s ``mesh_fallback``).
        """
        start = time.perf_counter()
        p_out = (
            DEFAULT_PRESSURES_MBAR.copy()
            if pressures_mbar is None
            else np.asarray(pressures_mbar, dtype=float)
        )
        if p_out[0] != 0 or np.any(np.diff(p_out) <= 0):
            raise ParameterError("pressures must start at 0 and increase strictly")
        deflection = np.full(p_out.shape, np.nan)
        deflection[0] = 0.0

        u = self.field[0].values
        u_now, u_before = u.copy(), u.copy()
        p_now, dp_last = 0.0, 0.0
        iterations, reason, lu = 0, "", None
        # increments grow to the widest spacing of the outputs (a curve refined
        # near 0 would otherwise creep on at its first, smallest step)
        nominal = float(np.max(np.diff(p_out))) if len(p_out) > 1 else 0.0
        if iteration_budget is None:
            iteration_budget = 20 * len(p_out)
        dp = nominal
        for k, target in enumerate(p_out[1:], start=1):
            while p_now < target - 1e-12:
                if iterations > iteration_budget:
                    reason = (
                        f"no equilibrium above {p_now:g} mbar (iteration budget of "
                        f"{iteration_budget} spent)"
                    )
                    break
                remaining = target - p_now
                if remaining <= 1e-6 * nominal:
                    # round-off of the sum of cut-back increments: the equilibrium
                    # is this pressure's to 1e-6 of an increment (a solve here would
                    # also make the next increment start from this sliver)
                    p_now = target
                    break
                clipped = remaining <= dp
                step = remaining if clipped else dp
                p_next = target if clipped else p_now + step
                # linear extrapolation of the last converged increment, unless it
                # inverts an element (then Newton starts from the last equilibrium)
                scale = step / dp_last if dp_last > 0 else 0.0
                u[:] = u_now + scale * (u_now - u_before)
                self._set_pressure(p_next)
                with np.errstate(all="ignore"):
                    f = self._residual()
                if not np.all(np.isfinite(f)):
                    u[:], f = u_now, None
                try:
                    with np.errstate(all="ignore"):
                        lu, used = self._equilibrium(p_next, lu, tol, maxiter, f=f,
                                                     stall_after=stall_after)
                    iterations += used
                    if used > 2:
                        # a hard increment: its last tangent would mislead the next
                        lu = None
                except (NoEquilibrium, RuntimeError, ValueError, np.linalg.LinAlgError) as err:
                    # the budget counts the iterations spent, not the ones allowed
                    iterations += getattr(err, "iterations", maxiter)
                    lu, dp = None, step / 4
                    if dp < min_increment_mbar:
                        reason = (
                            f"no equilibrium above {p_now:g} mbar (increment cut back "
                            f"below {min_increment_mbar:g} mbar: {err})"
                        )
                        break
                    continue
                self._commit()
                u_before, u_now = u_now, u.copy()
                p_now, dp_last = p_next, step
                # an increment cut short by an output pressure says nothing of the
                # increment size: it stays (doubling from a sliver would creep)
                if not clipped:
                    dp = min(2 * dp, nominal)
            if reason:
                break
            deflection[k] = self.apex_deflection()
            if progress is not None:
                progress(k, len(p_out) - 1, float(target))

        u[:] = u_now
        self._residual()  # leave the bodies' stored state at the last equilibrium
        converged = not reason
        if reason:
            reason += "; " + self.distortion_note(p_out, deflection)
        last = p_now if converged else float(p_out[np.flatnonzero(np.isfinite(deflection))[-1]])
        return Curve(
            pressure_mbar=p_out,
            deflection_mm=deflection,
            converged=converged,
            last_converged_mbar=float(p_out[-1]) if converged else last,
            reason=reason,
            newton_iterations=iterations,
            dofs=self.dofs,
            seconds=time.perf_counter() - start,
            info=dict(self.parameters, mesh=self.settings.to_dict(), engine=self.engine),
        )


def simulate(
    skin,
    probe=6.0,
    pressures_mbar=None,
    mesh=None,
    iteration_budget=None,
    progress=None,
    engine=None,
    stall_after=8,
):
    """Apex deflection M(p) of a skin under a suction probe.

    Parameters
    ----------
    skin : Skin
        The stack of layers and the bottom condition (e.g.
        ``Skin.two_layer(x1d, x1h)``, the paper's dermis over hypodermis, 1 mm
        each; :meth:`Skin.with_layer_on_top` adds a superficial layer). A layer's
        ``prestretch`` is its equibiaxial in-plane pre-stretch lambda0 (natural skin
        tension), applied before the probe is glued: each layer contracts through
        its thickness so that the surface stays traction-free, and the outer radius
        holds the tension; the thicknesses are those of the pre-stretched skin.
    probe : Probe or float, optional
        The probe, or its aperture diameter in mm (2 and 6 mm in the paper).
    pressures_mbar : array_like or Ramp, optional
        Suction pressures in mbar, from 0, ascending (default 0, 2, ..., 100).
    mesh : dict or MeshSettings, optional
        Discretisation settings (see :class:`MeshSettings`).
    iteration_budget : int, optional
        Newton iterations before the solver gives up (default 20 per pressure).
    progress : callable, optional
        Called as ``progress(k, n, pressure_mbar)`` after each pressure reached.
    engine : {"auto", "fast", "felupe"}, optional
        Overrides the mesh settings' ``engine``: the model's own assembly
        (``"auto"``, the default, takes it wherever it applies) or FElupe's, the
        reference. ``Curve.info["engine"]`` says which ran.
    stall_after : int, optional
        Newton iterations of an increment before a stalled one is cut back.

    Returns
    -------
    Curve
        The deflection curve; ``converged`` is False if the solver stopped early.
        ``Curve.info["skin"]`` records the skin.

    Examples
    --------
    >>> curve = simulate(Skin.two_layer(0.08, 4.1e-4), probe=2, pressures_mbar=[0, 50, 100],
    ...                  mesh={"refinement": 0.5})
    >>> curve.converged, bool(0.02 < curve.deflection_mm[-1] < 0.04)
    (True, True)
    """
    if isinstance(pressures_mbar, Ramp):
        pressures_mbar = pressures_mbar.pressures_mbar
    model = SuctionTest(skin, probe, _mesh_settings(mesh, engine))
    return model.run(pressures_mbar, iteration_budget=iteration_budget, progress=progress,
                     stall_after=stall_after)
