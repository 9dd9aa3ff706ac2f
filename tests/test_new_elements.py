"""Elements as data (symgen/domains.py, symgen/closed.py) and meshes of any kind
(runtime/element/reference.py): exact integration over the declared domains, the fast closed forms
against direct symbolic integration, interpolation of every element file, meshing by
connectivity, and cantilevers of the new elements against beam theory."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from conftest import KINDS

from runtime import Element
from runtime.element import reference as geometry
from runtime.kernels.kind import element_kind
from runtime.model import mesh as meshing
from symgen import closed, derive, domains
from symgen.elements import get, registry


@pytest.mark.parametrize("domain", [domains.beam(2), domains.beam(3), domains.plate()],
                         ids=["beam2d", "beam3d", "plate"])
def test_exact_integration_over_the_declared_domain(domain):
    """Term-by-term integration of a polynomial equals SymPy's integral over the bounds, and
    the subdomains have the documented measures."""
    coords = domain.coordinates
    poly = sum((i + 2) * c ** (i + 1) for i, c in enumerate(coords)) + coords[0] ** 3 * (
        coords[1] ** 2 + 1)
    direct = poly
    for c, low, high in domain.bounds():
        direct = sp.integrate(direct, (c, low, high))
    if domain.thickness is not None:
        direct *= domain.thickness
    assert sp.simplify(domain.integrate(poly) - direct) == 0
    a, b, c = domain.parameters
    assert domain.integrate(1) == a * b * c
    for name, _ in domain.subdomains:
        assert domain.integrate(1, name) == a * b * c  # extents of the fixed axes included


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_closed_forms_equal_direct_symbolic_integration(kind):
    """A sample of int P_kl P_mn (the isotropic i4) and int s_k s_l from the exact tables
    against SymPy integrating the products of the shape-function gradients directly (both
    canonical sums of monomials in the parameters: expanded, their difference is 0)."""
    spec = get(kind)
    grads = derive.shape_gradients(spec)
    tables = closed.straight_tables(spec)
    rng = np.random.default_rng(5)
    n = spec.n_shape
    pairs = derive.pairs(n)
    coordinates = spec.domain.coordinates

    def product(k: int, l_: int) -> sp.Poly:
        """P_kl = s_k,x . s_l,x as a polynomial in the local coordinates (SymPy's Poly
        arithmetic: the brick's products in a third of the time of expanding them)."""
        return sum((sp.Poly(grads[k, c], *coordinates) * sp.Poly(grads[l_, c], *coordinates)
                    for c in range(spec.dim)), sp.Poly(0, *coordinates))

    for a, b in [tuple(x) for x in rng.choice(len(pairs), size=(6, 2))]:
        (k, l_), (m, q) = pairs[a], pairs[b]
        direct = spec.domain.integrate_poly(product(k, l_) * product(m, q))
        key = (min(a, b), max(a, b))
        assert sp.expand(closed.to_sympy(spec, tables.i4.get(key, {})) - direct) == 0
    k, m = 0, n - 1
    direct = spec.domain.integrate(sp.expand(spec.shape_functions[k] * spec.shape_functions[m]))
    assert sp.expand(closed.to_sympy(spec, tables.mass[(k, m)]) - direct) == 0


@pytest.mark.parametrize("name", list(registry()))
def test_every_element_file_interpolates_its_nodal_vectors(name):
    get(name).check_interpolation()


def test_kinds_come_from_the_generated_metadata():
    assert set(KINDS) == set(registry())
    assert {"beam2d", "beam3d", "beam2d_3node", "beam3d_3node", "plate3d"} <= set(KINDS)
    plate = element_kind("plate3d")
    assert plate.meta["domain"]["name"] == "plate" and plate.n_nodes == 4
    assert list(plate.meta["laws"]) == ["svk"] and "ecm" in plate.meta["laws_not_applicable"]
    np.testing.assert_allclose(plate.node_points(2.0, 0.5, 0.1),
                               [[0, 0, 0], [2, 0, 0], [2, 0.5, 0], [0, 0.5, 0]])


def test_structured_meshes_share_nodes_by_position():
    beam = element_kind("beam3d_3node")
    mesh = meshing.structured_mesh(beam, 3)
    assert mesh.connectivity.tolist() == [[0, 1, 2], [2, 3, 4], [4, 5, 6]]
    np.testing.assert_allclose(mesh.points[:, 0], np.arange(7) / 2)
    assert mesh.dofs(beam).shape == (3, 27) and mesh.dofs(beam)[1, 0] == 2 * 9
    plate = element_kind("plate3d")
    mesh = meshing.structured_mesh(plate, (2, 2))
    assert mesh.connectivity.tolist() == [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6],
                                          [4, 5, 8, 7]]
    assert mesh.points.shape == (9, 2)
    with pytest.raises(ValueError, match="counts"):
        meshing.structured_mesh(plate, 3)
    e0 = geometry.rectangle_reference(plate, [0, 0, 0], [1.0, 0, 0], [0, 0.5, 0])
    np.testing.assert_allclose(e0, plate.straight_reference(1.0, 0.5, 0.05))
    with pytest.raises(ValueError, match="not a line element"):
        geometry.straight_reference(plate, [0, 0, 0], [1, 0, 0])


def static_tip_deflection(kind: str, counts, law: str, nu: float, load: float) -> float:
    """Linear static tip deflection (z) of a clamped strip 1 m long (0.1 x 0.05 m section;
    a plate: 0.1 m wide, 0.05 m thick) meshed by connectivity, a total ``load`` (N) along -z
    at the free end, shared equally by the free end's nodes."""
    info = element_kind(kind)
    mesh = meshing.structured_mesh(info, counts)
    m = np.atleast_1d(counts)
    length = 1.0 / m[0]
    width = 0.1 / (m[1] if len(m) > 1 else 1)
    el = Element(kind, length, width if len(m) > 1 else 0.1, 0.05, 2.1e11, nu, 7800.0,
                 backend="numpy", law=law)
    dofs = mesh.dofs(info)
    size = len(mesh.points) * info.per_node
    stiffness = np.zeros((size, size))
    jacobian = -el.elastic_jacobian(el.e0)
    for row in dofs:
        stiffness[np.ix_(row, row)] += jacobian
    clamped = np.flatnonzero(mesh.points[:, 0] == 0)
    tip = np.flatnonzero(mesh.points[:, 0] == mesh.points[:, 0].max())
    z = info.vectors.index("r") * info.dim + 2
    force = np.zeros(size)
    force[tip * info.per_node + z] = -load / len(tip)
    fixed = (clamped[:, None] * info.per_node + np.arange(info.per_node)).ravel()
    free = np.setdiff1d(np.arange(size), fixed)
    u = np.zeros(size)
    u[free] = np.linalg.solve(stiffness[np.ix_(free, free)], force[free])
    return float(-u[tip * info.per_node + z].mean())


def test_three_node_beam_cantilever_matches_euler_bernoulli():
    """beam3d_3node (ECM, as Chrono's 3333) meshed by connectivity: 8 elements within 0.5 %
    of P L^3 / 3 E I, at nu = 0.3 (no Poisson locking)."""
    load, inertia = 10.0, 0.1 * 0.05**3 / 12
    exact = load * 1.0**3 / (3 * 2.1e11 * inertia)
    assert static_tip_deflection("beam3d_3node", 8, "ecm", 0.3, load) == pytest.approx(
        exact, rel=5e-3)


def test_plate_strip_cantilever_matches_euler_bernoulli():
    """plate3d as a clamped strip (8 x 1 elements, nu = 0: no plate stiffening): within 2 %
    of P L^3 / 3 E I."""
    load, inertia = 10.0, 0.1 * 0.05**3 / 12
    exact = load * 1.0**3 / (3 * 2.1e11 * inertia)
    assert static_tip_deflection("plate3d", (8, 1), "svk", 0.0, load) == pytest.approx(
        exact, rel=2e-2)
