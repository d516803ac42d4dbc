"""Graded axisymmetric mesh of the two skin layers under the probe."""

from dataclasses import asdict, dataclass

import felupe as fem
import numpy as np


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
        Element size at the aperture edge, as a fraction of ``a``.
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
    """

    refinement: float = 1.0
    element: str = "quad8"
    quadrature: str = "reduced"
    formulation: str = "displacement"
    outer_radius_factor: float = 3.0
    edge_size: float = 0.006
    far_size: float = 0.4
    growth: float = 1.5
    probe_wall: bool = True
    wall_penalty: float = 10.0
    edge_radius: float = 0.0

    @classmethod
    def from_dict(cls, settings=None):
        """Build from a (config) dict, naming any unknown key."""
        settings = dict(settings or {})
        known = cls.__dataclass_fields__
        unknown = sorted(set(settings) - set(known))
        if unknown:
            raise ValueError(
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
        raise ValueError(f"a refinement above 1 must be a whole number, not {parts!r}")
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
    a = probe_mm / 2
    depth = t_d + t_h
    coarsening = min(settings.refinement, 1.0)
    h_edge = settings.edge_size * a / coarsening
    h_far = settings.far_size * (a + depth) / coarsening
    g = settings.growth
    outer = settings.outer_radius_factor * (a + depth)

    # radius: fine at the aperture edge on both sides, coarser at the axis and outside;
    # a rounded edge gets nodes at both of its ends and fine elements between them
    r_in = two_sided(0.0, a, 4 * h_edge, h_far, g, size_at_b=h_edge)
    glued = a * (1 + settings.edge_radius)
    r_edge = [a]
    if settings.edge_radius > 0:
        r_edge = two_sided(a, glued, h_edge, h_far, g, size_at_b=h_edge)
    r_out = two_sided(glued, outer, h_edge, h_far, g)
    r = np.concatenate([r_in, r_edge[1:], r_out[1:]])

    # depth: fine under the surface, a node line on the dermis/hypodermis interface
    z_d = -graded_coordinates(t_d, h_edge, h_far, g)
    h_interface = abs(z_d[-1] - z_d[-2])
    z_h = -t_d - graded_coordinates(t_h, h_interface, h_far, g)
    z = np.sort(np.concatenate([z_d, z_h[1:]]))
    if settings.refinement > 1:
        r, z = subdivide(r, settings.refinement), subdivide(z, settings.refinement)

    mesh = fem.mesh.Grid(z, r)
    mesh = mesh.add_midpoints_edges()
    if settings.element == "quad9":
        mesh = mesh.add_midpoints_faces()
    elif settings.element != "quad8":
        raise ValueError(f"mesh element must be 'quad8' or 'quad9', not {settings.element!r}")

    centroid_z = mesh.points[mesh.cells[:, :4], 0].mean(axis=1)
    is_dermis = centroid_z > -t_d
    return mesh, is_dermis
