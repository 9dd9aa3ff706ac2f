"""Mesh files of the shipped curved-shell scenes, written with meshio (gmsh is not needed):
``python -m runtime.studies.shell_meshes [FOLDER]`` (default ``scenes/``).

* ``roof.vtu``: the hinged cylindrical roof of Sze, Liu and Lo (2004, Finite Elements in
  Analysis and Design 40, 1551-1569, section 3.5): radius R = 2.54 m, length L = 0.508 m
  along the axis (y), opening angle 0.2 rad (phi in [-0.1, 0.1] about the apex, x = R sin
  phi, z = R (cos phi - cos 0.1): the straight edges at z = 0), quad8 cells of the 8-node
  shells (8 x 8 elements), counter-clockwise seen from outside (normals outward).
* ``hemisphere.vtu``: a quarter (longitude 0 to 90 degrees) of the pinched hemisphere of
  Sze, Liu and Lo: radius 10, a hole of 18 degrees about the pole, cut by
  meridians and parallels into 16 x 16 quad8 cells (its elements differ from ring to ring:
  16 element shapes), for ``scenes/hemisphere.toml``.

Both carry the exact surface normals as point data ``normal`` and 0/1 point data node sets
(the roof: ``hinged``, the straight edges; ``centre``, the apex node; the hemisphere:
``xz_plane`` and ``yz_plane``, the meridians on the symmetry planes y = 0 and x = 0;
``equator`` and ``hole``, the free edges;
``A`` and ``B``, the load points on the equator at (R, 0, 0) and (0, R, 0); ``top``, the
node of the hole's edge on the plane y = 0).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from runtime.model.mesh_file import CELL_NODES

ROOF = {"radius": 2.54, "length": 0.508, "angle": 0.2}
HEMISPHERE_RADIUS = 10.0
HEMISPHERE_HOLE_DEG = 18.0    # the polar hole's half-angle (degrees from the pole)


def quad8_grid(nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """The quad8 cells (nu nv, 8) of an nu x nv grid of elements on the unit square and the
    (u, v) parameters (points, 2) of its points: corners and mid-sides, numbered along u,
    then v (meshio's quad8 node order, counter-clockwise in u, v)."""
    lattice = {}
    cells = []
    local = np.array(CELL_NODES["quad8"]) * 2
    for j in range(nv):
        for i in range(nu):
            cell = []
            for du, dv in local.astype(int):
                key = (2 * j + dv, 2 * i + du)
                cell.append(lattice.setdefault(key, len(lattice)))
            cells.append(cell)
    keys = sorted(lattice)
    renumber = np.empty(len(keys), int)
    for new, key in enumerate(keys):
        renumber[lattice[key]] = new
    uv = np.array([(i / (2 * nu), j / (2 * nv)) for j, i in keys])
    return renumber[np.array(cells)], uv


def roof(nu: int = 8, nv: int = 8, radius: float = ROOF["radius"],
         length: float = ROOF["length"], angle: float = ROOF["angle"]):
    """The roof's meshio mesh (see the module docstring): nu elements around, nv along."""
    import meshio

    cells, uv = quad8_grid(nu, nv)
    phi = (uv[:, 0] - 0.5) * angle
    points = np.column_stack([radius * np.sin(phi), uv[:, 1] * length,
                              radius * (np.cos(phi) - np.cos(angle / 2))])
    normals = np.column_stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)])
    hinged = np.isclose(uv[:, 0], 0) | np.isclose(uv[:, 0], 1)
    centre = np.isclose(uv[:, 0], 0.5) & np.isclose(uv[:, 1], 0.5)
    return meshio.Mesh(points, [("quad8", cells)], point_data={
        "normal": normals, "hinged": hinged.astype(np.int32),
        "centre": centre.astype(np.int32)})


def hemisphere(nu: int = 16, nv: int = 16, radius: float = HEMISPHERE_RADIUS):
    """A quarter of the pinched hemisphere (z >= 0, longitude 0 to 90 degrees) of nu
    elements around and nv from the equator to the hole at 72 degrees of latitude, cut by
    meridians and parallels (quad8 cells, outward normals)."""
    import meshio

    cells, uv = quad8_grid(nu, nv)
    longitude = uv[:, 0] * np.pi / 2
    latitude = uv[:, 1] * np.radians(90.0 - HEMISPHERE_HOLE_DEG)
    normals = np.column_stack([np.cos(latitude) * np.cos(longitude),
                               np.cos(latitude) * np.sin(longitude), np.sin(latitude)])
    normals[np.isclose(uv[:, 0], 1.0), 0] = 0.0      # on the plane x = 0 exactly
    equator, hole = np.isclose(uv[:, 1], 0.0), np.isclose(uv[:, 1], 1.0)
    meridian_xz, meridian_yz = np.isclose(uv[:, 0], 0.0), np.isclose(uv[:, 0], 1.0)
    sets = {"xz_plane": meridian_xz, "yz_plane": meridian_yz, "equator": equator,
            "hole": hole, "A": meridian_xz & equator,
            "B": meridian_yz & equator, "top": meridian_xz & hole}
    return meshio.Mesh(radius * normals, [("quad8", cells)], point_data={
        "normal": normals, **{name: flags.astype(np.int32) for name, flags in sets.items()}})


def write(folder: Path) -> list[Path]:
    """Write roof.vtu and hemisphere.vtu into ``folder``; returns their paths."""
    import meshio

    paths = []
    for name, mesh in (("roof.vtu", roof()), ("hemisphere.vtu", hemisphere())):
        path = folder / name
        meshio.write(path, mesh, file_format="vtu", binary=True)
        paths.append(path)
    return paths


if __name__ == "__main__":
    for written in write(Path(sys.argv[1] if len(sys.argv) > 1 else "scenes")):
        print(f"wrote {written} ({written.stat().st_size} bytes)")
