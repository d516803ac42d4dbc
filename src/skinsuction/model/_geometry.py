"""Graded axisymmetric mesh of the two skin layers under the probe."""

from dataclasses import asdict, dataclass

import felupe as fem
import numpy as np

from ._curve import ParameterError


@dataclass(frozen=True)
class MeshSettings:
    """Discretisation of the suction-test model.

    Element sizes scale with the aperture radius ``a`` and are divided by
    ``refinement``; they are smallest at the aperture edge (where the dome bends
    sharply) and grow geometrically away from it.

    Parameters
    ----------
    refinement : float
        Above 1, a whole number: every element is split into ``refinement**2``
        (nested meshes, for convergence studies). Below 1, every element size is
        divided by it (coarser meshes for quick runs).
    element : {"quad8", "quad9"}
        Serendipity or Lagrange quadratic quadrilaterals.
    corner : {"fan", "grid"}
        Mesh around the aperture edge, where the skin glued to the probe meets the
        skin pulled into it. ``"fan"``: rings of elements around the edge, cut by
        spokes, so the skin can turn about the edge (by up to 90 degrees, onto the
        probe wall) while each element only opens or closes like a wedge. ``"grid"``:
        the graded tensor grid continues to the edge, whose corner elements shear
        (and tangle, for a soft dermis) as the skin turns.
    fan_size : float
        Half-width of the square fan region around the aperture edge, as a fraction
        of ``a``.
    fan_divisions : int
        Elements along each side of the fan square; the fan has ``4 fan_divisions``
        spokes, and its rings grow by ``1 + 1 / fan_divisions`` (square elements).
    quadrature : {"full", "reduced"}
        3x3 (full) or 2x2 (reduced) Gauss points. Reduced, as in the paper: with the
        penalty at nu = 0.49 it converges monotonically under mesh refinement, where
        full integration locks partly (see the mesh-convergence benchmark).
    formulation : {"displacement", "mixed"}
        Pure displacement with the volumetric penalty at the Gauss points, or a
        mixed form with cell-wise constant pressure and volume ratio.
    outer_radius_factor : float
        Outer radius of the model as a multiple of ``a + t_d + t_h``.
    edge_size : float
        Element size at the aperture edge, as a fraction of ``a``: the radius of the
        fan's innermost ring, or the grid's corner element.
    far_size : float
        Largest element size, as a fraction of ``a + t_d + t_h``.
    growth : float
        Largest ratio of neighbouring element sizes.
    probe_wall : bool
        Frictionless contact of the skin with the rigid inner wall of the probe.
    wall_penalty : float
        Penalty of the wall contact, relative to the mean nodal stiffness.
    edge_radius : float
        Radius of the rounded edge between the probe's wall and its glued face, as
        a fraction of ``a`` (0: a sharp edge). The skin is glued from ``a (1 +
        edge_radius)`` outwards and slides on the rounded edge inside that radius.
    engine : {"auto", "fast", "felupe"}
        Who assembles the residual and the tangent: this model's own NumPy
        assembly (``"fast"``, see :mod:`skinsuction.model._fast`) or FElupe's
        general one (``"felupe"``, the reference). Both give the same residual
        and tangent to round-off. The fast path covers the displacement
        formulation with a sharp probe edge; ``"auto"`` takes it there and
        FElupe's for ``formulation="mixed"`` or ``edge_radius > 0``.
    """

    refinement: float = 1.0
    element: str = "quad8"
    corner: str = "fan"
    fan_size: float = 0.1
    fan_divisions: int = 3
    quadrature: str = "reduced"
    formulation: str = "displacement"
    outer_radius_factor: float = 3.0
    edge_size: float = 0.03
    far_size: float = 0.4
    growth: float = 1.5
    probe_wall: bool = True
    wall_penalty: float = 10.0
    edge_radius: float = 0.0
    engine: str = "auto"

    @classmethod
    def from_dict(cls, settings=None):
        """Build from a (config) dict, naming any unknown key."""
        settings = dict(settings or {})
        known = cls.__dataclass_fields__
        unknown = sorted(set(settings) - set(known))
        if unknown:
            raise ParameterError(
                f"unknown mesh setting(s) {unknown}; known: {sorted(known)}"
            )
        return cls(**settings)

    def to_dict(self):
        return asdict(self)


def graded_coordinates(length, size_start, size_end, growth):
    """Node coordinates on ``[0, length]`` with element sizes growing geometrically
    from ``size_start`` at 0 towards ``size_end``, by at most ``growth`` per element.

    Examples
    --------
    >>> x = graded_coordinates(1.0, 0.01, 0.2, 1.3)
    >>> float(x[0]), float(x[-1]), bool(np.all(np.diff(x) > 0))
    (0.0, 1.0, True)
    """
    size_start = min(size_start, length)
    sizes = []
    total, size = 0.0, size_start
    while total + size < length * (1 - 1e-9):
        sizes.append(size)
        total += size
        size = min(size * growth, size_end)
    sizes = np.array(sizes or [length])
    # spread the remainder over all elements so that the last one is not a sliver
    sizes *= length / sizes.sum()
    x = np.concatenate([[0.0], np.cumsum(sizes)])
    x[-1] = length  # exactly, not to the round-off of the sum
    return x


def subdivide(x, parts):
    """Split every interval of ``x`` into ``parts`` equal ones (nested meshes).

    Examples
    --------
    >>> subdivide(np.array([0.0, 1.0, 3.0]), 2).tolist()
    [0.0, 0.5, 1.0, 2.0, 3.0]
    """
    if parts != int(parts):
        raise ParameterError(f"a refinement above 1 must be a whole number, not {parts!r}")
    parts = int(parts)
    t = np.arange(parts) / parts
    inner = (x[:-1, None] + np.diff(x)[:, None] * t).ravel()
    return np.append(inner, x[-1])


def two_sided(a, b, size_at_a, size_far, growth, size_at_b=None):
    """Coordinates on ``[a, b]`` fine at ``a`` (and at ``b`` if ``size_at_b``)."""
    if size_at_b is None:
        return a + graded_coordinates(b - a, size_at_a, size_far, growth)
    mid = 0.5 * (a + b)
    left = a + graded_coordinates(mid - a, size_at_a, size_far, growth)
    right = b - graded_coordinates(b - mid, size_at_b, size_far, growth)[::-1]
    return np.concatenate([left, right[1:]])


def _half_square(t):
    """Offsets (z, r) on the boundary of the unit half-square below the aperture
    edge: ``t`` from 0 to 4 runs from the free surface (0, -1) down, across and up
    to the glued face (0, 1)."""
    t = np.asarray(t, dtype=float)
    z = np.where(t < 1, -t, np.where(t < 3, -1.0, t - 4))
    r = np.where(t < 1, -1.0, np.where(t < 3, t - 2, 1.0))
    return np.stack([z, r], axis=-1)


def edge_fan(a, size, inner, divisions, parts=1):
    """Quadrilateral rings about the aperture edge ``(z, r) = (0, a)`` that fill the
    square ``[-size, 0] x [a - size, a + size]``.

    The ``4 divisions`` spokes end on the square's sides at a spacing of
    ``size / divisions``; the rings shrink geometrically from the square to the
    innermost one, of radius ``inner``, whose cells collapse onto the edge.

    Examples
    --------
    Eight spokes; rings of radius 0.03, 0.045, 0.067 and 0.1 about the centre:

    >>> fan = edge_fan(1.0, 0.1, 0.03, 2)
    >>> fan.ncells, bool(np.allclose(fan.points.min(axis=0), [-0.1, 0.9]))
    (32, True)
    """
    growth = 1 + 1 / divisions
    rings = max(1, int(np.ceil(np.log(size / inner) / np.log(growth))))
    rho = np.concatenate([[0.0], np.geomspace(inner, size, rings + 1)])
    rho[-1] = size
    t = np.linspace(0.0, 4.0, 4 * divisions + 1)
    if parts > 1:
        rho, t = subdivide(rho, parts), subdivide(t, parts)
    fan = fem.mesh.Grid(rho, t)
    fan.update(points=_half_square(fan.points[:, 1]) * fan.points[:, [0]] + [0.0, a])
    # (rho, t) -> (z, r) reverses the orientation of the cells
    return fem.mesh.flip(fan)


def suction_mesh(probe_mm, t_d, t_h, settings=MeshSettings()):
    """Quadratic quadrilateral mesh of the dermis (top) over the hypodermis.

    FElupe's axisymmetric fields take coordinate 0 as the axis (z, up) and
    coordinate 1 as the radius (r). The skin surface is ``z = 0``; the bottom is
    ``z = -(t_d + t_h)``.

    Returns
    -------
    mesh : felupe.Mesh
        The mesh (``quad8`` or ``quad9`` cells).
    is_dermis : ndarray of bool
        Per cell, True in the dermis.
    """
    if settings.element not in ("quad8", "quad9"):
        raise ParameterError(f"mesh element must be 'quad8' or 'quad9', not {settings.element!r}")
    if settings.corner == "fan":
        mesh = _fan_mesh(probe_mm, t_d, t_h, settings)
    elif settings.corner == "grid":
        mesh = _grid_mesh(probe_mm, t_d, t_h, settings)
    else:
        raise ParameterError(f"mesh corner must be 'fan' or 'grid', not {settings.corner!r}")
    mesh = mesh.add_midpoints_edges()
    if settings.element == "quad9":
        mesh = mesh.add_midpoints_faces()
    centroid_z = mesh.points[mesh.cells[:, :4], 0].mean(axis=1)
    return mesh, centroid_z > -t_d


def _sizes(probe_mm, t_d, t_h, settings):
    a = probe_mm / 2
    coarsening = min(settings.refinement, 1.0)
    return dict(
        a=a,
        h_edge=settings.edge_size * a / coarsening,
        h_far=settings.far_size * (a + t_d + t_h) / coarsening,
        outer=settings.outer_radius_factor * (a + t_d + t_h),
    )


def _fan_mesh(probe_mm, t_d, t_h, settings):
    if settings.edge_radius > 0:
        raise ParameterError("a rounded probe edge (edge_radius > 0) needs mesh corner 'grid'")
    s = _sizes(probe_mm, t_d, t_h, settings)
    a, g = s["a"], settings.growth
    size = min(settings.fan_size * a, 0.5 * t_d)
    divisions = max(1, round(settings.fan_divisions * min(settings.refinement, 1.0)))
    h_fan = size / divisions
    inner = min(s["h_edge"], size / (1 + 1 / divisions))
    parts = settings.refinement if settings.refinement > 1 else 1  # subdivide checks it

    # a tensor grid, uniform where it meets the fan's square, with the square cut out
    r = np.concatenate([
        two_sided(0.0, a - size, h_fan, s["h_far"], g, size_at_b=h_fan),
        a + size * np.linspace(-1.0, 1.0, 2 * divisions + 1)[1:],
        two_sided(a + size, s["outer"], h_fan, s["h_far"], g)[1:],
    ])
    z_d = -size - graded_coordinates(t_d - size, h_fan, s["h_far"], g)
    h_interface = abs(z_d[-1] - z_d[-2])
    z_h = -t_d - graded_coordinates(t_h, h_interface, s["h_far"], g)
    z = np.sort(np.concatenate([-size * np.linspace(0.0, 1.0, divisions + 1), z_d[1:], z_h[1:]]))
    if parts > 1:
        r, z = subdivide(r, parts), subdivide(z, parts)
    grid = fem.mesh.Grid(z, r)
    centre = grid.points[grid.cells].mean(axis=1)
    in_square = (centre[:, 0] > -size) & (np.abs(centre[:, 1] - a) < size)
    # drop the square's points, not only its cells (they would be unused DOFs)
    used, cells = np.unique(grid.cells[~in_square], return_inverse=True)
    grid.update(points=grid.points[used], cells=cells.reshape(-1, 4))

    fan = edge_fan(a, size, inner, divisions, parts)
    mesh = fem.mesh.concatenate([grid, fan]).merge_duplicate_points(decimals=10)
    # the fan shares its square's boundary with the grid and collapses its centre
    shared, collapsed = 4 * divisions * int(parts) + 1, 4 * divisions * int(parts)
    if mesh.npoints != grid.npoints + fan.npoints - shared - collapsed:
        raise RuntimeError("the fan mesh does not match the grid around it")
    return mesh


def _grid_mesh(probe_mm, t_d, t_h, settings):
    s = _sizes(probe_mm, t_d, t_h, settings)
    a, g, h_edge, h_far = s["a"], settings.growth, s["h_edge"], s["h_far"]

    # radius: fine at the aperture edge on both sides, coarser at the axis and outside;
    # a rounded edge gets nodes at both of its ends and fine elements between them
    r_in = two_sided(0.0, a, 4 * h_edge, h_far, g, size_at_b=h_edge)
    glued = a * (1 + settings.edge_radius)
    r_edge = [a]
    if settings.edge_radius > 0:
        r_edge = two_sided(a, glued, h_edge, h_far, g, size_at_b=h_edge)
    r_out = two_sided(glued, s["outer"], h_edge, h_far, g)
    r = np.concatenate([r_in, r_edge[1:], r_out[1:]])

    # depth: fine under the surface, a node line on the dermis/hypodermis interface
    z_d = -graded_coordinates(t_d, h_edge, h_far, g)
    h_interface = abs(z_d[-1] - z_d[-2])
    z_h = -t_d - graded_coordinates(t_h, h_interface, h_far, g)
    z = np.sort(np.concatenate([z_d, z_h[1:]]))
    if settings.refinement > 1:
        r, z = subdivide(r, settings.refinement), subdivide(z, settings.refinement)
    return fem.mesh.Grid(z, r)
