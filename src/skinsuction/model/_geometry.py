"""Graded axisymmetric mesh of a stack of skin layers under the probe."""

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
        Outer radius of the model as a multiple of ``a`` plus the stack's depth.
    edge_size : float
        Element size at the aperture edge, as a fraction of ``a``: the radius of the
        fan's innermost ring, or the grid's corner element.
    far_size : float
        Largest element size, as a fraction of ``a`` plus the stack's depth.
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
    node_lines_mm : tuple of float
        Depths (mm below the surface) of extra horizontal node lines, besides the
        layer interfaces (which always are node lines): a mesh of one stack that
        another stack's interfaces cut the same way (e.g. to compare a layer split
        in two identical ones with the whole layer).
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
    node_lines_mm: tuple = ()

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

    def __post_init__(self):
        object.__setattr__(self, "node_lines_mm", tuple(float(v) for v in self.node_lines_mm))

    def to_dict(self):
        """The settings as a dict (``node_lines_mm`` only when set, so the records of
        meshes without extra lines read as before it existed)."""
        out = asdict(self)
        if not out["node_lines_mm"]:
            del out["node_lines_mm"]
        else:
            out["node_lines_mm"] = list(out["node_lines_mm"])
        return out


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


def layer_breaks(thicknesses, node_lines_mm=()):
    """Depths (mm, positive, ascending) of every horizontal node line below the
    surface: the layer interfaces, any extra node line, and the bottom.

    Examples
    --------
    >>> layer_breaks([0.1, 0.9, 1.0]).tolist()
    [0.1, 1.0, 2.0]
    >>> layer_breaks([1.0, 1.0], node_lines_mm=[0.1]).tolist()
    [0.1, 1.0, 2.0]
    """
    t = np.asarray(thicknesses, dtype=float)
    if t.ndim != 1 or len(t) < 1 or not np.all(t > 0):
        raise ParameterError(f"layer thicknesses must be positive, not {list(t)}")
    depth = np.cumsum(t)
    lines = [float(v) for v in node_lines_mm]
    if any(not 0 < v < depth[-1] for v in lines):
        raise ParameterError(
            f"node_lines_mm must lie inside the stack (0, {depth[-1]:g}) mm, not {lines}")
    breaks = np.unique(np.concatenate([depth, lines]))
    # lines closer than 1e-9 of the depth are one line
    keep = np.concatenate([np.diff(breaks) > 1e-9 * depth[-1], [True]])
    breaks = breaks[keep]
    breaks[-1] = depth[-1]
    return breaks


def _stack_lines(breaks, top, h_top, h_far, growth):
    """Node depths z (negative, descending) from ``z = -top`` through each segment
    between ``breaks``: each graded from the spacing its upper neighbour ends with."""
    z = [-top - graded_coordinates(breaks[0] - top, h_top, h_far, growth)]
    for upper, lower in zip(breaks[:-1], breaks[1:]):
        h = abs(z[-1][-1] - z[-1][-2])
        z.append(-upper - graded_coordinates(lower - upper, h, h_far, growth)[1:])
    return np.concatenate(z)


def suction_mesh(probe_mm, thicknesses, settings=MeshSettings()):
    """Quadratic quadrilateral mesh of a stack of layers (top first).

    FElupe's axisymmetric fields take coordinate 0 as the axis (z, up) and
    coordinate 1 as the radius (r). The skin surface is ``z = 0``; the bottom is
    ``z = -sum(thicknesses)``; every layer interface (and every depth of
    ``settings.node_lines_mm``) is a line of nodes.

    Parameters
    ----------
    probe_mm : float
        Aperture diameter (mm).
    thicknesses : sequence of float
        Layer thicknesses (mm), top first.
    settings : MeshSettings

    Returns
    -------
    mesh : felupe.Mesh
        The mesh (``quad8`` or ``quad9`` cells).
    layer : ndarray of int
        Per cell, the index of its layer (0: top).

    Examples
    --------
    >>> mesh, layer = suction_mesh(2.0, [0.1, 0.9, 1.0], MeshSettings(refinement=0.5))
    >>> sorted(set(layer.tolist()))
    [0, 1, 2]
    >>> bool(np.any(np.isclose(mesh.points[:, 0], -0.1)))
    True
    """
    if settings.element not in ("quad8", "quad9"):
        raise ParameterError(f"mesh element must be 'quad8' or 'quad9', not {settings.element!r}")
    breaks = layer_breaks(thicknesses, settings.node_lines_mm)
    if settings.corner == "fan":
        mesh = _fan_mesh(probe_mm, breaks, settings)
    elif settings.corner == "grid":
        mesh = _grid_mesh(probe_mm, breaks, settings)
    else:
        raise ParameterError(f"mesh corner must be 'fan' or 'grid', not {settings.corner!r}")
    mesh = mesh.add_midpoints_edges()
    if settings.element == "quad9":
        mesh = mesh.add_midpoints_faces()
    depth = -mesh.points[mesh.cells[:, :4], 0].mean(axis=1)
    interfaces = np.cumsum(np.asarray(thicknesses, dtype=float))[:-1]
    return mesh, np.searchsorted(interfaces, depth)


def _sizes(probe_mm, depth, settings):
    a = probe_mm / 2
    coarsening = min(settings.refinement, 1.0)
    return dict(
        a=a,
        h_edge=settings.edge_size * a / coarsening,
        h_far=settings.far_size * (a + depth) / coarsening,
        outer=settings.outer_radius_factor * (a + depth),
    )


def _fan_mesh(probe_mm, breaks, settings):
    if settings.edge_radius > 0:
        raise ParameterError("a rounded probe edge (edge_radius > 0) needs mesh corner 'grid'")
    s = _sizes(probe_mm, breaks[-1], settings)
    a, g = s["a"], settings.growth
    # the fan lies in the top layer (above its first node line)
    size = min(settings.fan_size * a, 0.5 * breaks[0])
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
    z_stack = _stack_lines(breaks, size, h_fan, s["h_far"], g)
    z = np.sort(np.concatenate([-size * np.linspace(0.0, 1.0, divisions + 1), z_stack[1:]]))
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


def _grid_mesh(probe_mm, breaks, settings):
    s = _sizes(probe_mm, breaks[-1], settings)
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

    # depth: fine under the surface, a node line on every layer interface
    z = np.sort(_stack_lines(breaks, 0.0, h_edge, h_far, g))
    if settings.refinement > 1:
        r, z = subdivide(r, settings.refinement), subdivide(z, settings.refinement)
    return fem.mesh.Grid(z, r)
