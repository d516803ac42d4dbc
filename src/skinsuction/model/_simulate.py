"""The forward problem: apex deflection of the skin under a suction probe."""

import time

import felupe as fem
import numpy as np

from ._curve import Curve, ParameterError
from ._fast import FastAssembly, surface_edges
from ._geometry import MeshSettings, suction_mesh
from ._material import SkinLayers, bulk_modulus, thickness_stretch
from ._probe import ProbeEdge
from ._solver import NoEquilibrium, Stepping, TangentFactorizer, newton, reach
from ._skin import BOTTOM_CONDITIONS, Probe, Ramp, Skin

MBAR_TO_MPA = 1e-4
DEFAULT_PRESSURES_MBAR = np.arange(0.0, 101.0, 2.0)


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
        self.skin = skin
        self.layer_names = skin.names
        self.settings = mesh
        self.parameters = dict(skin=skin.to_dict(), probe_mm=probe_mm, bottom=skin.bottom,
                               poisson=poisson)
        try:  # the two-layer records keep the keys they always had
            self.parameters.update(skin.two_layer_values())
        except ParameterError:
            pass
        self.mesh, self.layer = suction_mesh(probe_mm, skin.thicknesses, mesh)
        a = probe_mm / 2
        # the skin is glued to the probe's face outside the rounded edge
        self._a, self._a_glued = a, a * (1 + mesh.edge_radius)
        if mesh.probe_wall:
            # reference point of the rigid probe, outside every cell; it lies on
            # the glued face, so it is fixed with it
            self.mesh.update(points=np.vstack([self.mesh.points, [0.0, self._a_glued]]))
        self._tol = 1e-9 * (a + skin.depth)

        quadrature = fem.GaussLegendre(order=2 if mesh.quadrature == "full" else 1, dim=2)
        if mesh.element == "quad9":
            region = fem.RegionBiQuadraticQuad(self.mesh, quadrature=quadrature)
            boundary_region = fem.RegionBiQuadraticQuadBoundary
        else:
            region = fem.RegionQuadraticQuad(self.mesh, quadrature=quadrature)
            boundary_region = fem.RegionQuadraticQuadBoundary
        self.field = fem.FieldContainer([fem.FieldAxisymmetric(region, dim=2)])
        umat, F0 = self._solid(poisson)
        inside = self._suction(boundary_region)
        self.items = [self.solid, self.suction]
        self._wall = self._probe_wall(inside)
        if self._wall is not None:
            self.items.append(self._wall)
        self._boundaries()
        self.engine = mesh.engine
        if self.engine == "auto":
            self.engine = "fast" if _fast_applies(mesh) else "felupe"
        self._pressure = 0.0  # FElupe's sign: suction is negative
        if self.engine == "fast":
            self.fast = FastAssembly(
                region, umat.x1, umat.x2, umat.bulk,
                None if F0 is None else np.asarray(F0),
                surface_edges(self.mesh.cells, self.mesh.points, inside),
                [] if self._wall is None else self._wall.points, self._a_glued,
                self.dof1, self.mesh.npoints,
                wall_center=None if self._wall is None else self._wall.centerpoint,
            )
            # the wall's penalty follows FElupe's: re-evaluated from the solid's
            # last tangent at the first evaluation of each increment
            self._wall_stale = True
        else:
            self._factorize = TangentFactorizer(self.dof1)

    def _solid(self, poisson):
        """The layers' body, per-cell parameters from the stack; the material and
        the pre-deformation F0 (or None)."""
        skin, mesh = self.skin, self.settings
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
        return umat, F0

    def _suction(self, boundary_region):
        """The follower pressure on the surface inside the aperture; its nodes' mask."""
        z, r = self.mesh.points.T
        inside = np.isclose(z, 0, atol=self._tol) & (r <= self._a_glued + self._tol)
        surface = boundary_region(self.mesh, only_surface=True, mask=inside, ensure_3d=True)
        self.suction = fem.SolidBodyPressure(
            fem.FieldContainer([fem.FieldAxisymmetric(surface, dim=2)])
        )
        return inside

    def _probe_wall(self, inside):
        """The skin inside the aperture cannot enter the probe: a frictionless rigid
        wall at r = a (penalty contact), inactive until a surface point is pulled
        outwards past the aperture edge; None without ``probe_wall``."""
        mesh = self.settings
        if not mesh.probe_wall:
            return None
        z, r = self.mesh.points.T
        free_top = np.flatnonzero(inside & (r < self._a_glued - self._tol))
        if mesh.edge_radius > 0:
            return ProbeEdge(
                self.field, points=free_top, centerpoint=len(z) - 1,
                edge_radius=mesh.edge_radius * self._a,
                multiplier=mesh.wall_penalty, items=[self.solid],
            )
        return fem.ContactRigidPlane(
            self.field, points=free_top, centerpoint=len(z) - 1,
            normal=[0.0, -1.0], multiplier=mesh.wall_penalty, items=[self.solid],
        )

    def _boundaries(self):
        """Axis, glued face, bottom (by the skin's condition) and, for a pre-stretched
        skin, the outer radius; the DOF partition and the apex node."""
        z, r = self.mesh.points.T
        tol, u = self._tol, self.field[0]
        boundaries = {
            "axis": fem.Boundary(u, mask=np.isclose(r, 0, atol=tol), skip=(1, 0)),
            "glued": fem.Boundary(
                u, mask=np.isclose(z, 0, atol=tol) & (r >= self._a_glued - tol)
            ),
        }
        bottom_nodes = np.isclose(z, -self.skin.depth, atol=tol)
        if self.skin.bottom == "fixed":
            boundaries["bottom"] = fem.Boundary(u, mask=bottom_nodes)
        elif self.skin.bottom == "axial":
            boundaries["bottom"] = fem.Boundary(u, mask=bottom_nodes, skip=(0, 1))
        if self.skin.has_prestretch:
            # the skin beyond the model holds the in-plane tension
            boundaries["outer"] = fem.Boundary(
                u, mask=np.isclose(r, r.max(), atol=tol), skip=(1, 0)
            )
        self.boundaries = boundaries
        self.dof0, self.dof1 = fem.dof.partition(self.field, boundaries)
        self.ext0 = fem.dof.apply(self.field, boundaries, self.dof0)
        self.apex = int(np.flatnonzero(np.isclose(z, 0, atol=tol) & np.isclose(r, 0, atol=tol))[0])
        self.dofs = self.field[0].values.size

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
               stall_window=4, keep_fresh=False):
        """Newton's method at the current load, in place (:func:`newton`, whose
        parameters these are); returns the tangent, the iterations and the residual."""
        return newton(self, lu, tol, maxiter, f, floor, xtol, stall_after, stall_window,
                      keep_fresh)

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

        # increments grow to the widest spacing of the outputs (a curve refined
        # near 0 would otherwise creep on at its first, smallest step)
        nominal = float(np.max(np.diff(p_out))) if len(p_out) > 1 else 0.0
        if iteration_budget is None:
            iteration_budget = 20 * len(p_out)
        u = self.field[0].values
        state = Stepping(u_now=u.copy(), u_before=u.copy(), dp=nominal, nominal=nominal)
        rules = dict(tol=tol, maxiter=maxiter, min_increment_mbar=min_increment_mbar,
                     iteration_budget=iteration_budget, stall_after=stall_after)
        reason = ""
        for k, target in enumerate(p_out[1:], start=1):
            reason = reach(self, float(target), state, **rules)
            if reason:
                break
            deflection[k] = self.apex_deflection()
            if progress is not None:
                progress(k, len(p_out) - 1, float(target))

        u[:] = state.u_now
        self._residual()  # leave the bodies' stored state at the last equilibrium
        converged = not reason
        if reason:
            reason += "; " + self.distortion_note(p_out, deflection)
        last = float(p_out[np.flatnonzero(np.isfinite(deflection))[-1]])
        return Curve(
            pressure_mbar=p_out,
            deflection_mm=deflection,
            converged=converged,
            last_converged_mbar=float(p_out[-1]) if converged else last,
            reason=reason,
            newton_iterations=state.iterations,
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
