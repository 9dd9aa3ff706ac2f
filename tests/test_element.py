"""Tests of ``runtime.Element``: invariance, derivatives, method/backend agreement, the
independent mpmath reference, round-off robustness, invariants and input validation.

Conventions and formulas come from DESIGN.md sections 3-5; expected values are computed here
from first principles (or by the mpmath reference of runtime/studies/highprecision.py),
never copied from the code under test.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
import sympy as sp
from conftest import (
    BACKENDS,
    E_MODULUS,
    HEIGHT,
    KINDS,
    LENGTH,
    METHODS,
    NU,
    RHO,
    WIDTH,
    arc_reference,
    degenerate_reference,
    dim_of,
    element,
    energy_scale,
    force_scale,
    invariant_rounding,
    inverted_reference,
    kind_seed,
    lame,
    position_mask,
    position_rows,
    random_rotation,
    rel_diff,
    rigid_cancellation,
    rigid_motion,
    straight_reference,
    translate,
)

from runtime import Element
from runtime.element import invariants as inv
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import kernel_family
from runtime.studies import highprecision as reference

EPS = np.finfo(float).eps


VOLUME = LENGTH * HEIGHT * WIDTH
SHAPES = ["straight", "curved"]

all_kinds = pytest.mark.parametrize("kind", KINDS)
all_methods = pytest.mark.parametrize("method", METHODS)
all_backends = pytest.mark.parametrize("backend", BACKENDS)
all_shapes = pytest.mark.parametrize("shape", SHAPES)


def curved(shape: str) -> bool:
    return shape == "curved"


def deformed(el: Element, rng: np.random.Generator, amplitude: float = 1e-2,
             rotate: bool = False) -> np.ndarray:
    """The reference (optionally rigidly rotated) plus a random perturbation."""
    e = el.e0
    if rotate:
        e = rigid_motion(el.kind.name, e, random_rotation(el.kind.dim, rng), np.zeros(el.kind.dim))
    return e + amplitude * rng.standard_normal(el.ndof)


def shape_matrix(el: Element, packed: np.ndarray) -> np.ndarray:
    """Full symmetric n x n matrix from a stored upper triangle (row-major)."""
    n = el.ndof // el.kind.dim
    full = np.zeros((n, n))
    rows, cols = np.triu_indices(n)
    full[rows, cols] = full[cols, rows] = packed
    return full


def gram_sum_scale(el: Element) -> float:
    """|g|^T |Dm| |g| (J) at e = 0, g = -Q0 Q0^T (positions taken from the first node's, as
    the kernels do): the sum of the magnitudes of the terms of the gram energy there."""
    kind = el.kind
    q0 = el.e0.reshape(kind.n_shape, kind.dim).copy()
    rows = list(kind.position_vectors)
    q0[rows] -= q0[rows[0]]
    g = np.abs((q0 @ q0.T)[np.triu_indices(kind.n_shape)])
    pattern = kind.pattern("straight", "gram")
    dm = np.zeros((g.size, g.size))
    dm[pattern[:, 0], pattern[:, 1]] = dm[pattern[:, 1], pattern[:, 0]] = el.invariants["gram"]
    return float(g @ np.abs(dm) @ g)


def u0_formula(kind: str, volume: float) -> float:
    """U0 of eqs. 40-41: (9 lam + 6 G)/8 V in 3D, (lam + G)/2 V in 2D; a cable (element.json
    ``energy``) has eps = -1/2 along its axis at e = 0: EA l / 8 = E V / 8."""
    if element_kind(kind).energy.structural:
        return E_MODULUS * volume / 8
    lam, shear = lame()
    return (9 * lam + 6 * shear) / 8 * volume if dim_of(kind) == 3 else (lam + shear) / 2 * volume


def test_conftest_straight_reference_matches_element_default():
    for kind in KINDS:
        np.testing.assert_array_equal(element(kind).e0, straight_reference(kind))
        assert element(kind).straight
        if "general" in element_kind(kind).energy.variants:
            assert not element(kind, curved=True).straight
        else:   # an energy for straight references only refuses a curved one, saying why
            with pytest.raises(ValueError, match="takes straight references only"):
                element(kind, curved=True)


# --- rigid motion ----------------------------------------------------------------------------


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_rigid_motion_gives_zero_force_and_energy(kind, method, backend, shape, rng):
    el = element(kind, method, backend, curved(shape))
    d = dim_of(kind)
    batch = np.array([rigid_motion(kind, el.e0, random_rotation(d, rng), rng.normal(size=d))
                      for _ in range(4)])
    force = el.elastic_force(batch)
    tolerance = 1e-9 * force_scale()
    if method == "cij":
        # F = -(K2(e) + K1) e sums terms of size |K| |e| that cancel at a rigid motion: what
        # is left is their rounding, a few eps |K| |e| per coordinate (|K| ~ the Jacobian;
        # for the plate's 48 coordinates and many more C^ij entries that is above 1e-9 E A)
        cancellation, size = rigid_cancellation(el, batch)
        tolerance = max(tolerance, cancellation)
    assert np.abs(force).max() <= tolerance
    energy = el.strain_energy(batch)
    if method == "cij":
        # eq. 39: U = 1/4 e^T K2 e + 1/2 e^T K1 e + U0 adds terms of size U0 ~ 1e6 times the
        # energy scale that cancel exactly at a rigid motion; what is left is the rounding of
        # those terms, a few eps * U0 (measured <= 8 eps; the kernels work relative to the
        # first node, so it does not grow with the translation).  32 eps * U0 bounds it; the
        # gram and quadrature methods form the strain first and are checked far tighter.
        tolerance = 32 * EPS * u0_formula(kind, VOLUME)
        # (the plate's quartic and quadratic terms are far above U0: their rounding, as for
        # the force, is a few eps |K| |e|^2 per coordinate)
        tolerance = max(tolerance, cancellation * size)
    else:
        tolerance = 1e-9 * energy_scale()
    assert np.abs(energy).max() <= tolerance


# --- derivatives -----------------------------------------------------------------------------


def central_difference(function, e: np.ndarray, step: float) -> np.ndarray:
    """Columns d function / d e_j by central differences, all 2 ndof evaluations in one batch."""
    shifts = step * np.eye(e.size)
    values = function(np.concatenate([e + shifts, e - shifts]))
    plus, minus = values[: e.size], values[e.size:]
    return (plus - minus) / (2 * step)


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_force_is_minus_energy_gradient(kind, method, backend, shape, rng):
    el = element(kind, method, backend, curved(shape))
    e = deformed(el, rng)
    step = 1e-6 * np.abs(e).max()
    gradient = central_difference(el.strain_energy, e, step)
    # cij's energy (eq. 39) sums terms that cancel, so its differences are noisier
    assert rel_diff(el.elastic_force(e), -gradient) <= (1e-5 if method == "cij" else 1e-6)


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_jacobian_is_force_derivative_and_symmetric(kind, method, backend, shape, rng):
    el = element(kind, method, backend, curved(shape))
    e = deformed(el, rng)
    step = 1e-6 * np.abs(e).max()
    jacobian = el.elastic_jacobian(e)
    assert jacobian.shape == (el.ndof, el.ndof)
    difference = central_difference(el.elastic_force, e, step).T  # row i: d force_i / d e_j
    assert rel_diff(jacobian, difference) <= 1e-6
    assert np.abs(jacobian - jacobian.T).max() <= 1e-12 * np.abs(jacobian).max()


# --- agreement of methods and backends -------------------------------------------------------


@functools.cache
def large_rotation_batch(kind: str, shape: str) -> np.ndarray:
    """Three random large-rotation configurations (reference rotated, plus 1e-2 noise)."""
    rng = np.random.default_rng([kind_seed(kind), SHAPES.index(shape), 7])
    el = element(kind, curved=curved(shape))
    return np.array([deformed(el, rng, rotate=True) for _ in range(3)])


@functools.cache
def results(kind: str, method: str, backend: str, shape: str):
    el = element(kind, method, backend, curved(shape))
    batch = large_rotation_batch(kind, shape)
    return el.elastic_force(batch), el.elastic_jacobian(batch), el.strain_energy(batch)


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_methods_and_backends_agree(kind, method, backend, shape):
    baseline = ("quadrature", "numpy") if (method, backend) != ("quadrature", "numpy") \
        else ("gram", "c")
    force, jacobian, energy = results(kind, method, backend, shape)
    force_b, jacobian_b, energy_b = results(kind, *baseline, shape)
    m, ndof = large_rotation_batch(kind, shape).shape
    assert force.shape == (m, ndof) and jacobian.shape == (m, ndof, ndof)
    assert energy.shape == (m,)
    assert rel_diff(force, force_b) <= 1e-10
    assert rel_diff(jacobian, jacobian_b) <= 1e-10
    # cij's energy (eq. 39) adds large terms that cancel: a digit fewer (as for mpmath), and
    # more rounding with more shape-function pairs (invariant_rounding)
    assert rel_diff(energy, energy_b) <= (1e-9 * invariant_rounding(kind)
                                          if "cij" in (method, baseline[0]) else 1e-10)


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_batch_equals_stacked_single_results(kind, method, backend, shape):
    el = element(kind, method, backend, curved(shape))
    batch = large_rotation_batch(kind, shape)
    force, jacobian, energy = results(kind, method, backend, shape)
    singles = [(el.elastic_force(e), el.elastic_jacobian(e), el.strain_energy(e)) for e in batch]
    assert all(f.shape == (el.ndof,) and j.shape == (el.ndof, el.ndof) and isinstance(u, float)
               for f, j, u in singles)
    # the same arithmetic per configuration: equal up to a rounding or two at most (the
    # looped NumPy kernels of large elements use BLAS products, whose summation order may
    # depend on the batch size: a few roundings more)
    tolerance = 1e-12 if backend == "numpy" else 1e-14
    assert rel_diff(np.stack([s[0] for s in singles]), force) <= tolerance
    assert rel_diff(np.stack([s[1] for s in singles]), jacobian) <= tolerance
    assert rel_diff(np.array([s[2] for s in singles]), energy) <= tolerance


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_combined_force_and_jacobian_kernel(kind, method, backend, shape):
    """The one-pass force + Jacobian kernel gives what the separate kernels give, into the
    caller's buffers when asked."""
    el = element(kind, method, backend, curved(shape))
    batch = large_rotation_batch(kind, shape)
    force, jacobian, _ = results(kind, method, backend, shape)
    out_force, out_jacobian = np.full_like(force, np.nan), np.full_like(jacobian, np.nan)
    both = el.elastic_force_and_jacobian(batch, out_force=out_force, out_jacobian=out_jacobian)
    tolerance = 1e-12 if backend == "numpy" else 1e-14  # as in the test above
    assert np.shares_memory(both[0], out_force) and rel_diff(out_force, force) <= tolerance
    assert rel_diff(out_jacobian, jacobian) <= tolerance
    single_force, single_jacobian = el.elastic_force_and_jacobian(batch[0])
    assert single_force.shape == (el.ndof,) and single_jacobian.shape == (el.ndof, el.ndof)
    assert rel_diff(single_jacobian, jacobian[0]) <= tolerance
    buffer = np.zeros(el.ndof)
    assert el.elastic_force(batch[0], out=buffer) is not None
    assert rel_diff(buffer, force[0]) <= tolerance
    with pytest.raises(ValueError, match="out"):
        el.elastic_force(batch, out=np.zeros((len(batch), el.ndof), dtype=np.float32))


# --- the independent mpmath reference --------------------------------------------------------


@all_kinds
def test_element_file_has_the_shape_functions_of_its_node_layout(kind):
    """The reference integrates shape functions derived from the node layout (the
    interpolation conditions its nodal vectors state) or typed from the literature; the
    element file must define exactly those polynomials."""
    derived = reference.shape_functions(kind, "derived")
    own = reference.shape_functions(kind, "element")
    assert len(derived) == len(own) == element_kind(kind).n_shape
    for k, (expected, actual) in enumerate(zip(derived, own, strict=True)):
        assert sp.expand(expected - actual) == 0, (k, expected, actual)


@pytest.mark.parametrize("kind", sorted(reference.LITERATURE))
def test_shape_functions_derived_from_the_layout_are_the_literature_ones(kind):
    """The derivation (nodes and nodal vectors -> interpolating functions) reproduces every
    element typed from the literature, so a new element needs no second typed entry."""
    for k, (expected, actual) in enumerate(zip(reference.shape_functions(kind, "literature"),
                                               reference.derived(kind), strict=True)):
        assert sp.expand(expected - actual) == 0, (k, expected, actual)


def test_a_layout_that_does_not_determine_its_functions_is_refused(monkeypatch):
    """Two nodes at one point state dependent conditions: a named error, not a singular
    solve."""
    kind = element_kind("beam2d")
    twin = dataclasses.replace(kind, nodes=(kind.nodes[0], kind.nodes[0]))
    monkeypatch.setattr(reference, "element_kind", lambda name: twin)
    reference._derived.cache_clear()
    try:
        with pytest.raises(ValueError, match="not independent"):
            reference.derived("beam2d")
    finally:
        reference._derived.cache_clear()


def mp_reference(kind: str, e: np.ndarray, e0: np.ndarray) -> tuple[float, np.ndarray]:
    """50-digit (U, force) from the literature's shape functions, or those derived from the
    node layout for a kind not typed there (runtime/studies/highprecision.py)."""
    return reference.energy_and_force(kind, e, e0, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU)



@functools.cache
def mpmath_moderate(kind: str, shape: str):
    """One moderately strained large-rotation configuration and its 50-digit (U, force)."""
    rng = np.random.default_rng([kind_seed(kind), SHAPES.index(shape), 11])
    el = element(kind, curved=curved(shape))
    e = deformed(el, rng, rotate=True)
    energy, force = mp_reference(kind, e, el.e0)
    return e, energy, force


@all_kinds
@all_methods
@all_backends
@all_shapes
def test_matches_mpmath_reference(kind, method, backend, shape):
    el = element(kind, method, backend, curved(shape))
    e, energy, force = mpmath_moderate(kind, shape)
    # cij evaluates K(e) e with K = K2(e) + K1, two large terms that largely cancel at a
    # moderate strain: one to two digits fewer than forming the strain first
    force_tol, energy_tol = (1e-10, 1e-9) if method == "cij" else (1e-12, 1e-12)
    if method != "quadrature":   # it sums no invariants
        force_tol, energy_tol = (t * invariant_rounding(kind) for t in (force_tol, energy_tol))
    assert rel_diff(el.elastic_force(e), force) <= force_tol
    assert abs(el.strain_energy(e) - energy) <= energy_tol * abs(energy)


# --- round-off robustness --------------------------------------------------------------------

SHIFT = 1e6  # m, added to every position coordinate
GRID = 2.0**-30
TINY_STRAIN = 1e-9  # the noise on the reference of the tiny-strain configurations


@functools.cache
def mpmath_tiny_strain(kind: str, shape: str):
    """Reference + 1e-9 noise, positions on a 2**-30 grid, and its 50-digit (U, force).

    The translated copy must be the same configuration exactly, or the test would measure the
    rounding of the shift instead of the kernels: |x + 1e6| < 2**20, where doubles are spaced
    2**-33, so any multiple of 2**-30 of size ~1 plus 1e6 is exactly representable and the
    shifted positions minus 1e6 give back the unshifted ones bit for bit.
    """
    rng = np.random.default_rng([kind_seed(kind), SHAPES.index(shape), 13])
    el = element(kind, curved=curved(shape))
    e = el.e0 + TINY_STRAIN * rng.standard_normal(el.ndof)
    positions = position_mask(kind)
    e[positions] = np.round(e[positions] / GRID) * GRID
    shifted = translate(kind, e, SHIFT)
    np.testing.assert_array_equal(translate(kind, shifted, -SHIFT), e)
    energy, force = mp_reference(kind, e, el.e0)
    return e, shifted, energy, force


ROBUST_METHODS = pytest.mark.parametrize("method", ["gram", "quadrature"])


def tiny_strain_tolerance(kind: str) -> float:
    """Relative force and energy tolerance at the tiny strain: 1e-8 for the continuum kinds,
    whose kernels form the strain from node-relative positions; a cable forms its axial
    strain (r_x . r_x - 1) / 2 from the gradient itself, whose square (~1) rounds to
    2**-53, which is 1.1e-7 of a strain of 1e-9: the bound of that formula (measured up to
    1.2e-8, draw by draw)."""
    if element_kind(kind).energy.structural:
        return np.finfo(float).eps / 2 / TINY_STRAIN
    return 1e-8


@all_kinds
@ROBUST_METHODS
@all_backends
@all_shapes
def test_tiny_strain_matches_mpmath(kind, method, backend, shape):
    el = element(kind, method, backend, curved(shape))
    e, _, energy, force = mpmath_tiny_strain(kind, shape)
    # a strain of 1e-9 gives forces ~1e-7 of those of a 1e-2 strain: the force is a small
    # difference if the kernels are careless (e.g. Q Q^T of the raw coordinates loses 9
    # digits at once)
    assert np.abs(force).max() <= 1e-5 * np.abs(mpmath_moderate(kind, shape)[2]).max()
    tolerance = tiny_strain_tolerance(kind)
    assert rel_diff(el.elastic_force(e), force) <= tolerance
    assert abs(el.strain_energy(e) - energy) <= tolerance * energy




@all_kinds
@ROBUST_METHODS
@all_backends
@pytest.mark.parametrize("shape", ["straight", "curved"])
def test_tiny_strain_translated_far_from_origin(kind, method, backend, shape):
    """The same configuration moved by 1e6 m (reference e0 unchanged): same force and energy.

    The arc's positions do not lie on the configuration's 2**-30 grid, so the displacement
    e - e0 is not exactly representable: the kernels must work from the node-relative
    positions (with their rounding errors carried exactly).
    """
    el = element(kind, method, backend, curved(shape))
    _, shifted, energy, force = mpmath_tiny_strain(kind, shape)
    tolerance = tiny_strain_tolerance(kind)
    assert rel_diff(el.elastic_force(shifted), force) <= tolerance
    assert abs(el.strain_energy(shifted) - energy) <= tolerance * energy


@functools.cache
def mpmath_tiny_strain_on_grid(kind: str):
    """Arc reference and a 1e-9 strained configuration, all positions on the 2**-30 grid."""
    rng = np.random.default_rng([kind_seed(kind), 17])
    positions = position_mask(kind)
    e0 = arc_reference(kind)
    e0[positions] = np.round(e0[positions] / GRID) * GRID
    e = e0 + 1e-9 * rng.standard_normal(e0.size)
    e[positions] = np.round(e[positions] / GRID) * GRID
    energy, force = mp_reference(kind, e, e0)
    return e0, e, energy, force


@functools.cache
def far_element(kind: str, method: str, backend: str) -> Element:
    e0, *_ = mpmath_tiny_strain_on_grid(kind)
    return Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO,
                   e0=translate(kind, e0, SHIFT), method=method, backend=backend)


@all_kinds
@ROBUST_METHODS
@all_backends
@pytest.mark.curved
def test_tiny_strain_with_element_far_from_origin(kind, method, backend):
    """A curved element whose reference and configuration both lie 1e6 m from the origin
    (a mesh far from the origin).  Both are on the 2**-30 grid, so the shifted pair is exactly
    the unshifted one moved, and its 50-digit reference is the unshifted one's."""
    el = far_element(kind, method, backend)
    assert not el.straight
    _, e, energy, force = mpmath_tiny_strain_on_grid(kind)
    shifted = translate(kind, e, SHIFT)
    np.testing.assert_array_equal(translate(kind, shifted, -SHIFT), e)
    # J0 is formed from the shifted positions: the invariants carry relative errors of about
    # ulp(1e6) / l ~ 1e-10, which the 1e-8 tolerance absorbs (they scale the force, not the
    # strain)
    assert rel_diff(el.elastic_force(shifted), force) <= 1e-8
    assert abs(el.strain_energy(shifted) - energy) <= 1e-8 * energy


# --- invariants ------------------------------------------------------------------------------


def quadrature_invariants(el: Element, orders) -> tuple[dict, inv.Integrals]:
    """The straight-variant invariants of ``el.e0`` through the quadrature path (for kinds
    whose closed forms are data tables or integrated at load time, through the law path with
    the svk coefficients)."""
    kind = element_kind(el.kind.name)
    builders = kernel_family(kind.name, "invariants", el.backend)
    if kind.energy.structural:  # a cable's J0 has no section: its integrals are on the axis
        return inv.cable_invariants(kind, builders, el.geometry, orders,
                                    el.law_coefficients(), RHO), None
    integrals = inv.numeric_integrals(kind, builders, el.geometry, el.e0, orders)
    if inv.through_laws(kind):
        rules = inv.law_rules(kind, builders, el.geometry, el.e0, orders)
        stored = inv.numeric_law_invariants(kind, builders, "straight", el.geometry, rules,
                                            el.law_coefficients(), RHO)
    else:
        stored = inv.stored_invariants(builders, "straight",
                                       inv.pattern_integrals(kind, "straight", integrals),
                                       (*lame(), RHO))
    return stored, integrals


@all_kinds
@all_methods
@all_backends
def test_symbolic_and_quadrature_invariants_agree(kind, method, backend):
    el = element(kind, method, backend)
    assert el.straight
    # the exact orders (5 x 3 [x 3] for the 2-node beams) integrate the polynomials of
    # int P P exactly (degree 8 in x and 4 in y, z there); a higher order must give the
    # same numbers
    exact = tuple(el.kind.meta["exact_orders"])
    for orders in (exact, tuple(o + 2 for o in exact)):
        numeric, integrals = quadrature_invariants(el, orders)
        assert set(numeric) == set(el.invariants) >= {"mass", "k1", "gram", "cij", "u0"}
        for name in numeric:
            assert el.invariants[name].shape == numeric[name].shape, name
            assert rel_diff(el.invariants[name], numeric[name]) <= 1e-12, name
        if integrals is None:  # a cable: the volume integrals of P P need a section
            continue
        # the straight storage pattern keeps every nonzero integral of P P
        n = el.ndof // el.kind.dim
        rows, cols = np.triu_indices(n)
        i4 = integrals.i4[rows[:, None], cols[:, None], rows[None, :], cols[None, :]]
        keys = el.kind.pattern("straight", "i4")
        kept = np.zeros(i4.shape, dtype=bool)
        kept[keys[:, 0], keys[:, 1]] = kept[keys[:, 1], keys[:, 0]] = True
        assert np.abs(i4[~kept]).max(initial=0.0) <= 1e-13 * np.abs(i4).max()
        assert integrals.volume == pytest.approx(VOLUME, rel=1e-14)


@all_kinds
@all_backends
def test_rigidly_placed_straight_reference_uses_the_same_invariants(kind, backend, rng):
    d = dim_of(kind)
    e0 = rigid_motion(kind, straight_reference(kind), random_rotation(d, rng), rng.normal(size=d))
    el = Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, e0=e0, backend=backend)
    assert el.straight
    for name, value in element(kind, backend=backend).invariants.items():
        assert rel_diff(el.invariants[name], value) <= 1e-13, name


# --- mass matrix -----------------------------------------------------------------------------


@all_kinds
@all_methods
@all_backends
def test_mass_matrix(kind, method, backend, rng):
    el = element(kind, method, backend)
    mass = el.mass_matrix()
    d, ndof = dim_of(kind), el.ndof
    assert mass.shape == (ndof, ndof)
    assert np.abs(mass - mass.T).max() <= 1e-15 * np.abs(mass).max()
    np.linalg.cholesky(mass)  # raises LinAlgError unless positive definite
    assert np.linalg.eigvalsh(mass).min() > 0
    total = RHO * VOLUME
    positions = position_mask(kind)
    nodes = el.kind.n_nodes
    for _ in range(3):
        u = rng.standard_normal(d)
        translation = np.zeros(ndof)
        translation[positions] = np.tile(u, nodes)
        # kinetic energy of a rigid translation: int rho |u|^2 dV
        assert translation @ mass @ translation == pytest.approx(total * u @ u, rel=1e-13)
        # M a for a rigid acceleration a: its position rows sum to the total force rho V a
        force = (mass @ translation).reshape(-1, d)[position_rows(kind)].sum(axis=0)
        np.testing.assert_allclose(force, total * u, rtol=1e-13, atol=1e-13 * total * abs(u).max())


# --- eqs. 39-41 ------------------------------------------------------------------------------


@all_kinds
@all_methods
@all_backends
def test_energy_constant_and_quadratic_terms(kind, method, backend, rng):
    """U(t e) = t^4/4 e^T K2 e + t^2/2 e^T K1 e + U0 (eq. 39) for every method."""
    el = element(kind, method, backend)
    u0 = u0_formula(kind, VOLUME)
    assert el.invariants["u0"].shape == (1,)
    assert el.invariants["u0"][0] == pytest.approx(u0, rel=1e-13)
    # e = 0 collapses the body to a point: E = -I/2 everywhere, U = U0, which the gram form
    # sums as g^T Dm g over every entry of its pattern (g = -Q0 Q0^T): rounding of the order of
    # eps |g|^T |Dm| |g|, 2.5e4 U0 for the plate, 3.7e5 U0 for the 8-node shell (measured
    # 0.003 to 0.36 of that bound over the kinds), 1e-12 U0 at least
    assert el.strain_energy(np.zeros(el.ndof)) == pytest.approx(
        u0, rel=1e-12, abs=np.finfo(float).eps * gram_sum_scale(el))
    e = deformed(el, rng, rotate=True)
    u_0, u_1, u_2 = el.strain_energy(np.array([0 * e, e, 2 * e]))
    quadratic = (16 * (u_1 - u_0) - (u_2 - u_0)) / 12
    k1 = np.kron(shape_matrix(el, el.invariants["k1"]), np.eye(el.kind.dim))
    # the gram energies round by their sum over the pattern (the brick's 32 shape functions:
    # 1.7e-11 of the quadratic term, where quadrature gives 3e-15 and cij 3e-14)
    rounding = invariant_rounding(kind) if method == "gram" else 1.0
    assert quadratic == pytest.approx(0.5 * e @ k1 @ e, rel=1e-11 * rounding)


@all_kinds
@all_backends
@all_shapes
def test_cij_energy_matches_gram_energy(kind, backend, shape, rng):
    gram = element(kind, "gram", backend, curved(shape))
    cij = element(kind, "cij", backend, curved(shape))
    e = deformed(gram, rng, rotate=True)
    u_gram = gram.strain_energy(e)
    assert u_gram > 1e-3 * energy_scale()  # a genuinely strained configuration
    assert cij.strain_energy(e) == pytest.approx(u_gram, rel=1e-9)


# --- input validation ------------------------------------------------------------------------

GOOD = dict(length=LENGTH, height=HEIGHT, width=WIDTH, E=E_MODULUS, nu=NU, rho=RHO)


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"length": -1.0}, "length"),
        ({"length": 0.0}, "length"),
        ({"height": -0.1}, "height"),
        ({"width": -0.05}, "width"),
        ({"E": -2.1e11}, "E"),
        ({"rho": -7800.0}, "rho"),
        ({"nu": 0.5}, "nu"),
        ({"nu": -1.0}, "nu"),
        ({"method": "galerkin"}, "method"),
        ({"backend": "fortran"}, "backend"),
    ],
)
@all_kinds
def test_bad_parameters(kind, changes, match):
    with pytest.raises(ValueError, match=match):
        Element(kind, **{**GOOD, **changes})


def test_unknown_kind_lists_known_kinds():
    with pytest.raises(ValueError, match="kind") as info:
        Element("plate9", **GOOD)
    assert all(kind in str(info.value) for kind in KINDS)


@all_kinds
@all_methods
@all_backends
def test_bad_coordinates(kind, method, backend):
    el = element(kind, method, backend)
    ndof = el.ndof
    for call in (el.elastic_force, el.elastic_jacobian, el.strain_energy):
        for bad in (np.zeros(ndof - 1), np.zeros((2, ndof + 1)), np.zeros((2, 2, ndof))):
            with pytest.raises(ValueError, match=rf"e: .*\({ndof},\)"):
                call(bad)
        nan = el.e0.copy()
        nan[3] = np.nan
        with pytest.raises(ValueError, match="e: .*NaN"):
            call(nan)
        with pytest.raises(ValueError, match="e: .*NaN"):
            call(np.stack([el.e0, nan]))


@all_kinds
@pytest.mark.parametrize("make", [
    inverted_reference,
    degenerate_reference,
], ids=["inverted", "degenerate"])
def test_bad_reference(kind, make):
    e0 = make(kind)
    if element_kind(kind).vectors[: dim_of(kind) + 1] == ("r", "r_x", "r_y", "r_z")[
            : dim_of(kind) + 1]:
        assert np.linalg.det(e0.reshape(-1, dim_of(kind))[1:dim_of(kind) + 1]) <= 0  # J0, node 1
    with pytest.raises(ValueError, match="e0"):
        Element(kind, **GOOD, e0=e0)


@all_kinds
def test_bad_reference_shape(kind):
    with pytest.raises(ValueError, match="e0"):
        Element(kind, **GOOD, e0=np.zeros(5))
