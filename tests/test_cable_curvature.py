"""The exact-curvature bending of the ANCF cables (law ``svk_exact_curvature``,
symgen/energies.py) against what does not share its code: the 50-digit mpmath quadrature of
the energy and its gradient (runtime/studies/highprecision.py), finite differences, Exudyn's
explicit formula for the bending force of its ANCFCable2D (written out here in NumPy), the
simple bending model where the two must agree, the other engine, and Exudyn itself on the
elastica.  The generic law tests (tests/test_law.py: methods and backends agreeing, rigid
motions, damping objectivity) and the cantilevers of tests/test_cable.py take the law too."""

from __future__ import annotations

import functools
import math
import subprocess
import sys

import numpy as np
import pytest
from conftest import (
    E_MODULUS,
    HEIGHT,
    LENGTH,
    METHODS,
    NU,
    RHO,
    WIDTH,
    dim_of,
    random_rotation,
    rel_diff,
    rigid_motion,
)
from scenes_small import body, compare_engines, scene

from runtime import (
    Arc,
    Body,
    Clamp,
    CosineRamp,
    Displacement,
    Dynamic,
    Element,
    Material,
    PointForce,
    Scene,
    SceneError,
    SectionForce,
    Static,
    load_scene,
    run_scene,
)
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model
from runtime.studies import cable_bending, highprecision, peers

LAW = "svk_exact_curvature"
CABLES = ["cable2d", "cable3d"]
ALPHA = 0.01  # s
all_cables = pytest.mark.parametrize("kind", CABLES)
all_methods = pytest.mark.parametrize("method", METHODS)


@functools.cache
def cable(kind: str, method: str = "gram", backend: str = "c", law: str = LAW,
          damping: float = ALPHA) -> Element:
    """The conftest element as a cable of ``law`` with Kelvin-Voigt damping."""
    return Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, method=method,
                   backend=backend, law=law, damping=damping)


def bent(kind: str, rng: np.random.Generator, amplitude: float = 0.05) -> np.ndarray:
    """A large rotation and translation of the reference plus ``amplitude`` noise (relative to
    the element's size): bent, stretched and twisted."""
    el = cable(kind)
    d = dim_of(kind)
    e = rigid_motion(kind, el.e0, random_rotation(d, rng), rng.normal(size=d))
    return e + amplitude * np.abs(el.e0).max() * rng.standard_normal(el.ndof)


def central_difference(function, x: np.ndarray, step: float) -> np.ndarray:
    """Rows d function / d x_j: (ndof, out)."""
    shifts = step * np.eye(x.size)
    values = function(np.concatenate([x + shifts, x - shifts]))
    return (values[: x.size] - values[x.size:]) / (2 * step)


# --- an independent NumPy cable: Hermite shape functions, Exudyn's bending formula --------


def hermite(x: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """(ds/dx, d2s/dx2) of the cubic Hermite shape functions [r(0), r_x(0), r(l), r_x(l)] at
    the points x: (points, 4) each."""
    xi = x / length
    first = np.column_stack([(-6 * xi + 6 * xi**2) / length, 1 - 4 * xi + 3 * xi**2,
                             (6 * xi - 6 * xi**2) / length, -2 * xi + 3 * xi**2])
    second = np.column_stack([(-6 + 12 * xi) / length**2, (-4 + 6 * xi) / length,
                              (6 - 12 * xi) / length**2, (-2 + 6 * xi) / length])
    return first, second


def gauss(order: int, length: float) -> tuple[np.ndarray, np.ndarray]:
    t, w = np.polynomial.legendre.leggauss(order)
    return (t + 1) * length / 2, w * length / 2


def planar_force(q: np.ndarray, length: float, EA: float, EI: float, axial: str = "green",
                 bending_order: int = 5) -> np.ndarray:
    """The planar cable's elastic force (8,) at the nodal vectors ``q`` (4, 2), its bending
    written out as Exudyn's ObjectANCFCable2D evaluates it (main/src/Objects/
    CObjectANCFCable2D.cpp, read for its formulas): per Gauss point of ``bending_order``
    kappa = f / g with f = r_x x r_xx, g = |r_x|^2, the force -EI kappa (df / g - 2 f dg / g^2)
    with df_j = s'_j (r_xx x e_i) + s''_j (e_i x r_xx) and dg_j = r_x,i s'_j; the axial force
    at 5 points with the Green strain (``green``, this project's: -EA eps s'_j r_x) or
    Exudyn's |r_x| - 1 (``biot``: -EA (|r_x| - 1) s'_j r_x / |r_x|)."""
    force = np.zeros((4, 2))
    x, w = gauss(bending_order, length)
    first, second = hermite(x, length)
    for p in range(x.size):
        rx, rxx = first[p] @ q, second[p] @ q
        f, g = rx[0] * rxx[1] - rx[1] * rxx[0], rx @ rx
        for j in range(4):
            df = np.array([first[p, j] * rxx[1] - second[p, j] * rx[1],
                           -first[p, j] * rxx[0] + second[p, j] * rx[0]])
            force[j] -= w[p] * EI * f / g * (df / g - 2 * f * rx * first[p, j] / g**2)
    x, w = gauss(5, length)
    first, _ = hermite(x, length)
    for p in range(x.size):
        rx = first[p] @ q
        norm = np.sqrt(rx @ rx)
        stress = (norm**2 - 1) / 2 if axial == "green" else (norm - 1) / norm
        force -= w[p] * EA * stress * np.outer(first[p], rx)
    return force.ravel()


def exudyn_style_force(e: np.ndarray) -> np.ndarray:
    """``planar_force`` of the conftest element."""
    return planar_force(e.reshape(4, 2), LENGTH, E_MODULUS * HEIGHT * WIDTH,
                        E_MODULUS * WIDTH * HEIGHT**3 / 12)


def planar_elastica_tip(elements: int, axial: str, start: np.ndarray | None = None):
    """The elastica of ``runtime.studies.cable_bending`` (3 bending points) solved here: the
    residual of ``planar_force`` assembled over the mesh, Newton with a central-difference
    Jacobian over cable_bending.LOAD_STEPS load steps (or from the nodal vectors ``start``,
    (elements + 1, 4), at the full load).  Returns the tip (x, y) displacement and the
    nodal vectors."""
    geometry = cable_bending.ELASTICA
    length, h, w = geometry["length"], geometry["height"], geometry["width"]
    EA, EI = cable_bending.YOUNG * w * h, cable_bending.YOUNG * w * h**3 / 12
    load, size = cable_bending.tip_force(), length / elements

    def residual(free: np.ndarray, scale: float) -> np.ndarray:
        nodes = np.vstack([[0.0, 0.0, 1.0, 0.0], free.reshape(elements, 4)])
        total = np.zeros_like(nodes)
        for i in range(elements):
            f = planar_force(nodes[i:i + 2].reshape(4, 2), size, EA, EI, axial, 3)
            total[i:i + 2] += f.reshape(2, 4)
        total[-1, 1] -= scale * load
        return total[1:].ravel()

    x = (np.column_stack([np.arange(1, elements + 1) * size, np.zeros((elements, 3))])
         + [0.0, 0.0, 1.0, 0.0]).ravel() if start is None else start[1:].ravel().copy()
    steps = cable_bending.LOAD_STEPS if start is None else 1
    for step in range(1, steps + 1):
        scale = step / steps
        for _ in range(30):
            r = residual(x, scale)
            jacobian = central_difference(lambda y, s=scale: np.array([residual(v, s)
                                                                       for v in y]), x, 1e-7).T
            dx = np.linalg.solve(jacobian, -r)
            x += dx
            if np.abs(dx).max() <= 1e-13:
                break
    nodes = x.reshape(elements, 4)
    return (nodes[-1, 0] - length, nodes[-1, 1]), nodes


def bending_dissipation(e: np.ndarray, e_dot: np.ndarray, step: float = 1e-7,
                        order: int = 5) -> float:
    """alpha EI/2 int kappa_dot^2 dx + alpha EA/2 int eps_dot^2 dx of the planar cable, the
    rates by central differences in time along e_dot (kappa = r_x x r_xx / |r_x|^2)."""
    x, w = gauss(order, LENGTH)
    first, second = hermite(x, LENGTH)

    def strains(coordinates):
        q = coordinates.reshape(4, 2)
        rx, rxx = first @ q, second @ q
        norm2 = np.einsum("pa,pa->p", rx, rx)
        return (rx[:, 0] * rxx[:, 1] - rx[:, 1] * rxx[:, 0]) / norm2, (norm2 - 1) / 2

    (k1, e1), (k0, e0) = strains(e + step * e_dot), strains(e - step * e_dot)
    kappa_dot, eps_dot = (k1 - k0) / (2 * step), (e1 - e0) / (2 * step)
    EA, EI = E_MODULUS * HEIGHT * WIDTH, E_MODULUS * WIDTH * HEIGHT**3 / 12
    return ALPHA / 2 * float(w @ (EI * kappa_dot**2 + EA * eps_dot**2))


# --- element ------------------------------------------------------------------------------


@all_cables
@all_methods
@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_matches_mpmath_reference(kind, method, backend):
    """Energy and force of a large-rotation, moderately bent configuration against 50-digit
    Gauss quadrature (the same 5 points along the axis) of the exact-curvature energy and its
    gradient written out in mpmath."""
    el = cable(kind, method, backend)
    e = bent(kind, np.random.default_rng([CABLES.index(kind), 7]))
    energy, force = highprecision.cable_energy_and_force(
        kind, e, LENGTH, HEIGHT, WIDTH, E_MODULUS, bending="exact_curvature")
    simple = highprecision.cable_energy_and_force(kind, e, LENGTH, HEIGHT, WIDTH, E_MODULUS)
    assert rel_diff(force, simple[1]) > 1e-3  # the two models differ at this curvature
    tolerance = 1e-10 if method == "cij" else 1e-12  # cij's K(e) e cancels large terms
    assert rel_diff(el.elastic_force(e), force) <= tolerance
    assert abs(el.strain_energy(e) - energy) <= tolerance * abs(energy)


@all_methods
def test_planar_force_is_exudyns_bending_formula(method, rng):
    """The 2D force against Exudyn's explicit derivative of kappa (``exudyn_style_force``)."""
    e = bent("cable2d", rng)
    assert rel_diff(cable("cable2d", method).elastic_force(e), exudyn_style_force(e)) <= 1e-10


@all_cables
@all_methods
def test_force_and_jacobian_are_derivatives(kind, method, rng):
    el = cable(kind, method)
    e = bent(kind, rng)
    step = 1e-6 * np.abs(e).max()
    assert rel_diff(el.elastic_force(e), -central_difference(el.strain_energy, e, step)) <= 1e-6
    jacobian = el.elastic_jacobian(e)
    assert rel_diff(jacobian, central_difference(el.elastic_force, e, step).T) <= 1e-6
    assert np.abs(jacobian - jacobian.T).max() <= 1e-12 * np.abs(jacobian).max()


@all_cables
@all_methods
def test_rotated_configuration_gives_the_rotated_force(kind, method, rng):
    """Objectivity of a bent state: F(R e + t) = R F(e) (the exact curvature is rotation
    invariant; the rigid motions of the reference, zero force: tests/test_law.py)."""
    el = cable(kind, method)
    d = dim_of(kind)
    e = bent(kind, rng)
    R, t = random_rotation(d, rng), rng.normal(size=d)
    rotate = lambda f: rigid_motion(kind, f, R, np.zeros(d))  # noqa: E731
    assert rel_diff(el.elastic_force(rigid_motion(kind, e, R, t)),
                    rotate(el.elastic_force(e))) <= 1e-11


@all_cables
def test_small_deflections_bend_as_the_simple_model(kind):
    """At the straight reference both models have the same transverse bending stiffness
    (kappa = r_x x dr_xx with r_x = e_x); the exact curvature leaves the axial component of
    r_xx free, which the simple model stiffens by EI int u''^2 dx (the only difference)."""
    exact = cable(kind, "gram").elastic_jacobian(cable(kind).e0)
    simple = cable(kind, "gram", law="svk").elastic_jacobian(cable(kind).e0)
    d = dim_of(kind)
    transverse = [i for i in range(exact.shape[0]) if i % d]
    axial = [i for i in range(exact.shape[0]) if i % d == 0]
    block = np.ix_(transverse, transverse)
    assert rel_diff(exact[block], simple[block]) <= 1e-12
    assert np.abs(exact[np.ix_(axial, transverse)]).max() <= 1e-12 * np.abs(exact).max()
    el = cable(kind, law="svk")
    moment = el.invariants["gram_linear"]  # the simple model's EI mu K / 4, upper pairs
    rows, cols = np.triu_indices(el.kind.n_shape)
    bending = np.zeros((el.kind.n_shape,) * 2)
    bending[rows, cols] = bending[cols, rows] = moment * np.where(rows == cols, 4, 2)
    difference = (simple - exact)[np.ix_(axial, axial)]
    assert rel_diff(-difference, bending) <= 1e-9


# --- damping -------------------------------------------------------------------------------


@all_cables
@all_methods
def test_damping_jacobians_are_the_damping_force_derivatives(kind, method, rng):
    el = cable(kind, method)
    e, e_dot = bent(kind, rng), rng.standard_normal(el.ndof)
    force, total_de, de_dot = el.internal_force_and_jacobians(e, e_dot)
    de = total_de - el.elastic_jacobian(e)
    step = 1e-6 * np.abs(e).max()
    assert rel_diff(de, central_difference(lambda x: el.damping_force(x, e_dot), e, step).T) \
        <= 1e-6
    assert rel_diff(de_dot, central_difference(lambda v: el.damping_force(e, v), e_dot,
                                               1e-3).T) <= 1e-9
    assert rel_diff(force, el.elastic_force(e) + el.damping_force(e, e_dot)) <= 1e-12


@all_methods
def test_planar_damping_dissipates_the_curvature_rate(method, rng):
    """-F_d . e_dot = 2 Phi with Phi = alpha EI/2 int kappa_dot^2 + alpha EA/2 int
    eps_dot^2 (the rates by finite differences in time of an independent kappa)."""
    el = cable("cable2d", method)
    e, e_dot = bent("cable2d", rng), rng.standard_normal(el.ndof)
    power = -el.damping_force(e, e_dot) @ e_dot
    assert power == pytest.approx(2 * bending_dissipation(e, e_dot), rel=1e-7)


# --- engines, physics and the peer ---------------------------------------------------------


@pytest.mark.parametrize("kind, placement", [("cable2d", "line"), ("cable3d", "line"),
                                             ("cable2d", "arc")])
def test_compiled_and_python_engines_agree(kind, placement):
    """A damped cantilever of exact-curvature cables (straight, or a quarter circle) swinging
    under a ramped tip load."""
    steel = Material("m", E=2.1e11, nu=0.0, rho=7800.0, law=LAW, damping=1e-3)
    zero = [0.0] * (dim_of(kind) - 2)
    beam = (Body("beam", kind, "m", 0.02, 0.02, 4, arc=Arc((0.0, 0.0), 1.0, 0.0, 90.0))
            if placement == "arc" else body("beam", kind, 4, (0.0, 0.0, *zero), (1.0, 0.0, *zero),
                                0.02, 0.02))
    scene_ = scene([beam], [Clamp("beam:0")],
                   [PointForce("beam:-1", (0.0, -400.0, *zero), time_law=CosineRamp(0.05))],
                   [Displacement("tip_y", "beam:-1", "y")], steel,
                   dynamic=Dynamic(t_end=0.05, step=1e-3))
    compare_engines(scene_, sensor_rtol=1e-10)


@functools.cache
def elastica_errors() -> dict[int, float]:
    """Tip error over L of the exact-curvature elastica by element count."""
    return {n: cable_bending.error(cable_bending.cable_tip(LAW, n))
            for n in cable_bending.COUNTS}


def test_elastica_converges_to_the_exact_elastica():
    """P L^2 / EI = 10, L / h = 200 (``runtime.studies.cable_bending``, docs/laws.md):
    measured 1.3e-2, 2.2e-3, 1.7e-4, 1.2e-5 at 4, 8, 16, 32 elements."""
    errors = elastica_errors()
    assert errors[16] <= 2e-4 and errors[32] <= 2e-5
    counts = sorted(errors)
    assert all(errors[a] / errors[b] >= 5 for a, b in zip(counts, counts[1:], strict=False))


@pytest.mark.skipif(not peers.exudyn_available(), reason="Exudyn is not installed")
@pytest.mark.parametrize("elements, bound", [(4, 2e-7), (16, 1e-8)])
def test_elastica_tip_agrees_with_exudyn(elements, bound):
    """Exudyn's ANCFCable2D has the same bending (r_x x r_xx / |r_x|^2, 3 Gauss points):
    with the same 3-point rule the tips agree to ``bound`` L (measured 7.3e-8 and 2.2e-9; the
    rest is the axial strain, |r_x| - 1 there, the Green strain here); with our default 5
    points the difference is the quadrature's (3e-5 at 4 elements)."""
    ours = cable_bending.cable_tip(LAW, elements, quadrature=3)
    theirs = cable_bending.exudyn_tip(elements)
    gap = max(abs(a - b) for a, b in zip(ours, theirs, strict=True))
    assert gap <= bound * cable_bending.ELASTICA["length"]


def test_bench_kernels_times_both_bending_models():
    result = subprocess.run(
        [sys.executable, "-m", "runtime.cli", "bench", "kernels", "--element", "cable2d",
         "--batch", "50", "--backend", "numpy", "--method", "gram"],
        capture_output=True, text=True, check=True, timeout=300)
    assert result.stdout.count(f"| {LAW} | numpy |") == 2      # batches 1 and 50
    assert result.stdout.count("| svk | numpy |") == 2
    assert f"- {LAW}/svk time ratio, gram, numpy, batch 50: force" in result.stdout


def test_elastica_is_the_written_out_model():
    """The whole static solution against an independent one: ``planar_elastica_tip`` (the
    NumPy cable with Exudyn's bending formula and the Green axial strain, 3 bending points)
    gives the scene's tip at 4 elements to round-off."""
    ours = cable_bending.cable_tip(LAW, 4, quadrature=3)
    theirs, _ = planar_elastica_tip(4, "green")
    assert max(abs(a - b) for a, b in zip(ours, theirs, strict=True)) <= 1e-12


@pytest.mark.skipif(not peers.exudyn_available(), reason="Exudyn is not installed")
def test_exudyn_is_the_written_out_model_with_its_axial_strain():
    """What is left between Exudyn and us is the axial strain measure: the NumPy cable with
    Exudyn's |r_x| - 1 (``biot``), converged from Exudyn's elastica, moves its tip by no more
    than Exudyn's Newton tolerance (measured 5.6e-10 L); with the Green strain it moves by
    the whole gap (7.3e-8 L)."""
    import exudyn as exu

    geometry = cable_bending.ELASTICA
    length, h, w = geometry["length"], geometry["height"], geometry["width"]
    E, elements = cable_bending.YOUNG, 4
    with peers._quiet():
        _, mbs, nodes = peers._clamped_cable(elements, length, 1.0, E * w * h**3 / 12,
                                            E * w * h, [0.0, -cable_bending.tip_force()], None)
        mbs.Assemble()
        settings = peers._settings(length)
        settings.staticSolver.numberOfLoadSteps = cable_bending.LOAD_STEPS
        mbs.SolveStatic(settings)
        solution = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates)
                             for n in nodes])
    solution += [[i * length / elements, 0.0, 1.0, 0.0] for i in range(elements + 1)]
    exudyn_tip = (solution[-1, 0] - length, solution[-1, 1])
    biot, _ = planar_elastica_tip(elements, "biot", solution)
    green, _ = planar_elastica_tip(elements, "green", solution)
    distance = lambda a: max(abs(u - v) for u, v in zip(a, exudyn_tip, strict=True))  # noqa: E731
    assert distance(biot) <= 5e-9 * length
    assert distance(green) >= 3e-8 * length


# --- curved references (the planar exact curvature, kappa - kappa0) -------------------------


def quarter_circle(radius: float) -> np.ndarray:
    """e0 of one cable2d element bent onto a quarter circle of ``radius`` from (radius, 0),
    counter-clockwise: r_x the unit tangent (x is arc length)."""
    ends = [0.0, math.pi / 2]
    return np.concatenate([[radius * math.cos(t), radius * math.sin(t), -math.sin(t),
                            math.cos(t)] for t in ends])


@all_methods
@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_quarter_circle_at_rest_or_moved_rigidly_has_zero_force(method, backend, rng):
    radius = 2 * LENGTH / math.pi
    e0 = quarter_circle(radius)
    el = Element("cable2d", LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, e0=e0, method=method,
                 backend=backend, law=LAW, damping=ALPHA)
    assert el.variant == "general"
    scale = E_MODULUS * HEIGHT * WIDTH  # EA (N); the bending forces are EI / R^2 ~ 1e-3 EA
    moved = rigid_motion("cable2d", e0, random_rotation(2, rng), rng.normal(size=2))
    for e in (e0, moved):
        assert np.abs(el.elastic_force(e)).max() <= 1e-12 * scale
        assert abs(el.strain_energy(e)) <= 1e-12 * scale * LENGTH
    bent_ = e0 + 0.05 * rng.standard_normal(el.ndof)
    assert np.abs(el.elastic_force(bent_)).max() >= 1e-3 * scale
    quadrature = Element("cable2d", LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, e0=e0,
                         method="quadrature", backend="numpy", law=LAW)
    assert rel_diff(el.elastic_force(bent_), quadrature.elastic_force(bent_)) <= 1e-12


ARC_LOAD = 1e-4 * 2.1e11 * 0.01**4 / 12   # N: P R^2 / EI = 1e-4 on the arc of ``arc_scene``


def arc_scene(elements: int) -> Scene:
    """A quarter-circle cantilever of radius 1 m (R / h = 100) from (1, 0) to (0, 1), clamped
    at (1, 0), under the tip force -P y (ARC_LOAD); sensors: the tip displacement, the
    section forces N and M3 at the middle of the first element and of element elements / 2
    (``N_first``, ``M3_middle``, ...)."""
    size = (math.pi / 2) / elements
    section = [SectionForce(f"{c}_{where}", "c", element, size / 2, c)
               for where, element in (("first", 0), ("middle", elements // 2))
               for c in ("N", "M3")]
    return Scene(title="quarter circle", materials=[Material("steel", 2.1e11, 0.0, 7800.0,
                                                             law=LAW)],
                 bodies=[Body("c", "cable2d", "steel", 0.01, 0.01, elements,
                              arc=Arc((0.0, 0.0), 1.0, 0.0, 90.0))],
                 constraints=[Clamp("c:0")], loads=[PointForce("c:-1", (0.0, -ARC_LOAD))],
                 sensors=[Displacement("tip_x", "c:-1", "x"),
                          Displacement("tip_y", "c:-1", "y"), *section],
                 static=Static(load_steps=1))


def arc_tip(elements: int) -> tuple[float, float]:
    """Tip displacement of ``arc_scene`` over P R^3 / EI."""
    result = run_scene(arc_scene(elements), progress=False)
    assert result.status == "ok", result.summary
    sensors = result.summary["static"]["sensors"]
    scale = ARC_LOAD / (2.1e11 * 0.01**4 / 12)
    return sensors["tip_x"] / scale, sensors["tip_y"] / scale


def test_quarter_circle_cantilever_is_castigliano():
    """The curved beam by Castigliano (bending energy only): with M(phi) = P R cos(phi),
    the tip moves by (-1/2, -pi/4) P R^3 / EI.  Measured: 1.3e-2 at 4 elements, 1.3e-3 at
    8, 6e-5 at 16 (the axial strain and the geometric nonlinearity are ~1e-4 here)."""
    exact = (-0.5, -math.pi / 4)
    for elements, bound in ((8, 2e-3), (16, 2e-4)):
        tip = arc_tip(elements)
        assert max(abs(a / b - 1) for a, b in zip(tip, exact, strict=True)) <= bound


def test_quarter_circle_section_forces_are_the_statics():
    """At rest the section forces of the arc vanish (the reference curvature and metric are
    subtracted: the Hermite arc's |r0_x| is not 1 between the nodes); under the tip load the
    bending moment is the statics of the arc, M3 = P R cos(phi) at the angle phi from the
    clamp (measured 1.6e-3 at 16 elements; the axial force from the strain, 8e-10 here, is
    left untested: it is within 4 to 36 % of -P cos(phi))."""
    elements = 16
    scene_ = arc_scene(elements)
    model = Model(scene_)
    at_rest = Sensors(model).values(model.reference, np.zeros_like(model.reference), 0.0)
    for name in ("N_first", "M3_first", "N_middle", "M3_middle"):
        assert abs(at_rest[name]) <= 1e-9 * ARC_LOAD
    loaded = run_scene(scene_, progress=False).summary["static"]["sensors"]
    size = (math.pi / 2) / elements
    for where, phi in (("first", size / 2), ("middle", (elements // 2 + 0.5) * size)):
        assert loaded[f"M3_{where}"] == pytest.approx(ARC_LOAD * math.cos(phi), rel=3e-3)


def test_simple_bending_refuses_an_arc():
    with pytest.raises(SceneError, match="svk.* takes straight references only: the cable "
                       "energy's simple bending model"):
        Scene(title="arc", materials=[Material("steel", 2.1e11, 0.0, 7800.0)],
              bodies=[Body("c", "cable2d", "steel", 0.01, 0.01, 4,
                           arc=Arc((0.0, 0.0), 1.0, 0.0, 90.0))])
    planar = quarter_circle(2 * LENGTH / math.pi).reshape(4, 2)
    with pytest.raises(ValueError, match="the 3D exact curvature"):
        Element("cable3d", LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, law=LAW,
                e0=np.column_stack([planar, np.zeros(4)]).ravel())


def test_study_tables():
    """The two tables of docs/laws.md (``runtime.studies.cable_bending``), on a small run."""
    costs = cable_bending.kernel_costs(("cable2d",), batch=20, repeats=1)
    assert [line.split(" | ")[1] for line in costs.splitlines()[2:]] == list(METHODS)
    elastica = cable_bending.table((4,))
    assert elastica.splitlines()[2].startswith("| 4 | 1.31e-02 | 1.31e-02 | 1.31e-02 |")


def test_continuum_kind_refuses_the_cable_law(tmp_path):
    path = tmp_path / "beam.toml"
    path.write_text(f"""
title = "beam"
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
law = "{LAW}"
[[body]]
name = "b"
element = "beam2d"
material = "steel"
section = {{ height = 0.1, width = 0.1 }}
elements = 2
start = [0.0, 0.0]
end = [1.0, 0.0]
""")
    with pytest.raises(SceneError, match="a law the continuum energy of beam2d has not"):
        load_scene(path)
