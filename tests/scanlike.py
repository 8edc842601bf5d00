"""Scan-like perturbations of synthetic solids, built here for the exploration tests.

Each returns a new watertight mesh whose true shape the test knows: vertex jitter on a finely
subdivided solid (a scan's noise), rounded edges (the convex hull of corner spheres), and
smooth bumps pushed out along the vertex normals (cardboard bulge, relief).
"""

from __future__ import annotations

import numpy as np
import trimesh

from tactile_kb.record import Contact


def subdivided(mesh: trimesh.Trimesh, edge: float) -> trimesh.Trimesh:
    """``mesh`` with every triangle split until its edges are at most ``edge`` long."""
    v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge=edge)
    return trimesh.Trimesh(v, f)


def jittered(
    mesh: trimesh.Trimesh, amplitude: float, *, seed: int, edge: float = 0.004
) -> trimesh.Trimesh:
    """Subdivided to ``edge``, every vertex moved by uniform noise of ±``amplitude`` per axis."""
    out = subdivided(mesh, edge)
    rng = np.random.default_rng(seed)
    out.vertices = out.vertices + rng.uniform(-amplitude, amplitude, out.vertices.shape)
    return out


def rounded_box(a: float, b: float, c: float, radius: float) -> trimesh.Trimesh:
    """An a × b × c box whose edges and corners are rounded with ``radius``."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=radius)
    half = np.array([a, b, c]) / 2 - radius
    corners = [np.array([sx, sy, sz]) * half for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    hull: trimesh.Trimesh = trimesh.convex.convex_hull(
        np.vstack([ball.vertices + k for k in corners])
    )
    return hull


def bumped(
    mesh: trimesh.Trimesh, height: float, *, bumps: int, seed: int, edge: float = 0.004
) -> trimesh.Trimesh:
    """Subdivided to ``edge``, with ``bumps`` smooth Gaussian bumps of ``height`` (and width
    four times ``edge``) pushed out along the vertex normals at random surface points."""
    out = subdivided(mesh, edge)
    rng = np.random.default_rng(seed)
    centres = out.vertices[rng.choice(len(out.vertices), bumps, replace=False)]
    width = 4.0 * edge
    d = np.linalg.norm(out.vertices[:, None, :] - centres[None, :, :], axis=2)
    lift = height * np.exp(-((d / width) ** 2)).max(axis=1)
    out.vertices = out.vertices + lift[:, None] * out.vertex_normals
    return out


def roughened(contact: Contact, rng: np.random.Generator, amplitude: float) -> Contact:
    """``contact`` moved along its face's normal by uniform noise of ±``amplitude``: a touch
    of a rough face (its relief about the plane), the tip centre and the point alike."""
    shift = -np.asarray(contact.direction) * rng.uniform(-amplitude, amplitude)
    return contact.model_copy(
        update={
            "centre": tuple(np.asarray(contact.centre) + shift),
            "point": tuple(np.asarray(contact.point) + shift),
        }
    )
