"""Bad calls at the Element / kernel boundary (issue 10, reliability audit).

Every bad call raises ValueError naming the argument and what was expected (type problems
included: one class for callers to catch), identically for the C and NumPy backends and for
every generated element kind; no kernel reads or writes past a buffer, reinterprets bytes,
writes into a read-only array, leaves an ``out`` unfilled or returns a silent NaN.

The corpora are rows ``(description, call, expected message fragment)``: ``call`` receives a
``Setup`` (the element under test and valid inputs) and makes one call; the fragment may use
``{ndof}``, ``{ndof2}`` (ndof squared), ``{dim}`` and ``{kind}``.  Adding a case is one line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pytest
from conftest import (
    BACKENDS,
    E_MODULUS,
    HEIGHT,
    KINDS,
    LENGTH,
    NU,
    RHO,
    WIDTH,
    degenerate_reference,
    dim_of,
    element,
    kind_seed,
)

from runtime import Element
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import kernel_family

GOOD = dict(length=LENGTH, height=HEIGHT, width=WIDTH, E=E_MODULUS, nu=NU, rho=RHO)


@dataclass
class Setup:
    """The gram element of one kind and backend, one valid e (ndof,) and a batch (3, ndof)."""

    kind: str
    backend: str

    def __post_init__(self) -> None:
        self.el = element(self.kind, "gram", self.backend)
        self.dim, self.ndof = dim_of(self.kind), self.el.ndof
        rng = np.random.default_rng(kind_seed(self.kind))
        self.batch = self.el.e0 + 1e-3 * rng.standard_normal((3, self.ndof))
        self.e = self.batch[0].copy()

    def make(self, **changes) -> Element:
        """An Element of this kind and backend with ``changes`` to the typical parameters."""
        kind = changes.pop("kind", self.kind)
        return Element(kind, **{**GOOD, "backend": self.backend, **changes})

    def group(self, kernel: str = "force"):
        return self.el.group_kernel(kernel)

    def one_shot(self, kernel: str, out: dict | None = None, **inputs):
        """A one-shot KernelFamily call of the element's kernels: ``gram`` (and a cable's
        ``gram_linear``) are the element's unless given, an input given as None is left out."""
        inputs = {**self.el.kernel_inputs, **inputs}
        family = kernel_family(self.kind, self.el.family, self.backend)
        return family(kernel, {k: v for k, v in inputs.items() if v is not None}, out)

    def e0s(self, rows: int) -> np.ndarray:
        return np.tile(self.el.e0, (rows, 1))

    def fragment(self, text: str) -> str:
        return text.format(ndof=self.ndof, ndof2=self.ndof**2, dim=self.dim, kind=self.kind)


@pytest.fixture(params=[(k, b) for k in KINDS for b in BACKENDS], ids=lambda p: "-".join(p))
def setup(request) -> Setup:
    return Setup(*request.param)


def raises(setup: Setup, call, fragment: str) -> str:
    """Run ``call``; it must raise ValueError whose message contains ``fragment``."""
    with pytest.raises(ValueError, match=re.escape(setup.fragment(fragment))) as info:
        call(setup)
    return str(info.value)


# --- bad arrays -------------------------------------------------------------------------------


def readonly(*shape: int) -> np.ndarray:
    array = np.zeros(shape)
    array.flags.writeable = False
    return array


def immutable(*shape: int) -> np.ndarray:
    """A float64 array backed by an immutable ``bytes`` object."""
    return np.frombuffer(bytes(8 * int(np.prod(shape)))).reshape(shape)


def fortran(*shape: int) -> np.ndarray:
    return np.zeros(shape, order="F")


def strided(*shape: int) -> np.ndarray:
    return np.zeros((*shape, 2))[..., 0]


# --- 1 and 3: Element out buffers (read-only, Fortran-ordered, ...) ---------------------------

OUT = "expected a writable C-contiguous float64 array of shape "

ELEMENT_OUT_CASES = [
    ("read-only out", lambda s: s.el.elastic_force(s.e, out=readonly(s.ndof)),
     "out: " + OUT + "({ndof},), got read-only float64"),
    ("out backed by bytes", lambda s: s.el.elastic_force(s.e, out=immutable(s.ndof)),
     "out: " + OUT + "({ndof},), got read-only float64"),
    ("read-only out, batch", lambda s: s.el.elastic_force(s.batch, out=readonly(3, s.ndof)),
     "out: " + OUT + "(3, {ndof}), got read-only"),
    ("read-only jacobian out",
     lambda s: s.el.elastic_jacobian(s.e, out=readonly(s.ndof, s.ndof)),
     "out: " + OUT + "({ndof}, {ndof}), got read-only"),
    ("read-only out_force",
     lambda s: s.el.elastic_force_and_jacobian(s.e, out_force=readonly(s.ndof)),
     "out_force: " + OUT + "({ndof},), got read-only"),
    ("bytes-backed out_jacobian",
     lambda s: s.el.elastic_force_and_jacobian(s.e, out_jacobian=immutable(s.ndof, s.ndof)),
     "out_jacobian: " + OUT + "({ndof}, {ndof}), got read-only"),
    ("Fortran out, batch force", lambda s: s.el.elastic_force(s.batch, out=fortran(3, s.ndof)),
     "out: " + OUT + "(3, {ndof}), got Fortran-ordered float64"),
    ("Fortran jacobian out", lambda s: s.el.elastic_jacobian(s.e, out=fortran(s.ndof, s.ndof)),
     "out: " + OUT + "({ndof}, {ndof}), got Fortran-ordered"),
    ("Fortran jacobian out, batch",
     lambda s: s.el.elastic_jacobian(s.batch, out=fortran(3, s.ndof, s.ndof)),
     "out: " + OUT + "(3, {ndof}, {ndof}), got Fortran-ordered"),
    ("Fortran out_jacobian, batch",
     lambda s: s.el.elastic_force_and_jacobian(s.batch, out_jacobian=fortran(3, s.ndof, s.ndof)),
     "out_jacobian: " + OUT + "(3, {ndof}, {ndof}), got Fortran-ordered"),
    ("Fortran out_force, batch",
     lambda s: s.el.elastic_force_and_jacobian(s.batch, out_force=fortran(3, s.ndof)),
     "out_force: " + OUT + "(3, {ndof}), got Fortran-ordered"),
    ("strided out", lambda s: s.el.elastic_force(s.e, out=strided(s.ndof)),
     "out: " + OUT + "({ndof},), got non-contiguous"),
    ("float32 out", lambda s: s.el.elastic_force(s.e, out=np.zeros(s.ndof, np.float32)),
     "out: " + OUT + "({ndof},), got float32"),
    ("big-endian out", lambda s: s.el.elastic_force(s.e, out=np.zeros(s.ndof, ">f8")),
     "out: " + OUT + "({ndof},), got >f8"),
    ("list out", lambda s: s.el.elastic_force(s.e, out=[0.0] * s.ndof),
     "out: " + OUT + "({ndof},), got list"),
    ("flat jacobian out", lambda s: s.el.elastic_jacobian(s.e, out=np.zeros(s.ndof**2)),
     "out: " + OUT + "({ndof}, {ndof}), got float64 array of shape ({ndof2},)"),
    ("batch-shaped out for one e", lambda s: s.el.elastic_force(s.e, out=np.zeros((1, s.ndof))),
     "out: " + OUT + "({ndof},), got float64 array of shape (1, {ndof})"),
    ("out with too few rows", lambda s: s.el.elastic_force(s.batch, out=np.zeros((2, s.ndof))),
     "out: " + OUT + "(3, {ndof}), got float64 array of shape (2, {ndof})"),
]


# --- 2: the public group kernel (BoundKernel) -------------------------------------------------

WIDTH_24 = "expected shape (m, {ndof}) float64 for {kind}, got "
REAL = "expected real numbers (float or integer), shape (m, {ndof}) float64 for {kind}, got "

GROUP_CASES = [
    ("e of the wrong width", lambda s: s.group()({"e": np.zeros((1, 10)), "e0": s.e0s(1)}),
     "e: " + WIDTH_24 + "(1, 10)"),
    ("e0 of the wrong width", lambda s: s.group()({"e": s.batch, "e0": np.zeros((1, 10))}),
     "e0: " + WIDTH_24 + "(1, 10)"),
    ("e0 with fewer rows than e", lambda s: s.group()({"e": s.batch, "e0": s.e0s(2)}),
     "e0: expected shape (3, {ndof}) or (1, {ndof}) float64 for {kind}"),
    ("e0 with more rows than e", lambda s: s.group()({"e": s.batch[:2], "e0": s.e0s(3)}),
     "e0: expected shape (2, {ndof}) or (1, {ndof}) float64 for {kind}"),
    ("empty e0 for a batch", lambda s: s.group()({"e": s.batch, "e0": s.e0s(0)}),
     "e0: expected shape (3, {ndof}) or (1, {ndof})"),
    ("one e (ndof,)", lambda s: s.group()({"e": s.e, "e0": s.e0s(1)}),
     "e: " + WIDTH_24 + "({ndof},)"),
    ("3-D e", lambda s: s.group()({"e": s.batch[None], "e0": s.e0s(1)}),
     "e: " + WIDTH_24 + "(1, 3, {ndof})"),
    ("scalar e", lambda s: s.group()({"e": 1.0, "e0": s.e0s(1)}), "e: " + WIDTH_24 + "()"),
    ("complex e", lambda s: s.group()({"e": s.batch + 0j, "e0": s.e0s(1)}),
     "e: " + REAL + "complex128 array"),
    ("complex e0", lambda s: s.group()({"e": s.batch, "e0": s.e0s(1) + 1j}),
     "e0: " + REAL + "complex128 array"),
    ("bool e", lambda s: s.group()({"e": s.batch > 0, "e0": s.e0s(1)}),
     "e: " + REAL + "bool array"),
    ("object e", lambda s: s.group()({"e": np.full((1, s.ndof), None), "e0": s.e0s(1)}),
     "e: " + REAL + "object array"),
    ("string e", lambda s: s.group()({"e": [["0.5"] * s.ndof], "e0": s.e0s(1)}),
     "e: " + REAL + "<U3 values"),
    ("ragged e", lambda s: s.group()({"e": [[0.0] * s.ndof, [0.0]], "e0": s.e0s(1)}),
     "e: expected real numbers, shape (m, {ndof}) float64 for {kind}; "),
    ("e is None", lambda s: s.group()({"e": None, "e0": s.e0s(1)}),
     "e: missing; the force kernel for {kind} takes e, e0"),
    ("missing e0", lambda s: s.group("energy")({"e": s.batch}),
     "e0: missing; the energy kernel for {kind} takes e, e0"),
    ("batch not a dict", lambda s: s.group()(s.batch), "batch: expected a dict"),
    ("out not a dict", lambda s: s.group()({"e": s.batch, "e0": s.e0s(1)}, np.zeros(3)),
     "out: expected a dict"),
    ("read-only out['force']",
     lambda s: s.group()({"e": s.batch, "e0": s.e0s(1)}, {"force": readonly(3, s.ndof)}),
     "out['force']: " + OUT + "(3, {ndof}), got read-only"),
    ("bytes-backed out['force']",
     lambda s: s.group()({"e": s.batch, "e0": s.e0s(1)}, {"force": immutable(3, s.ndof)}),
     "out['force']: " + OUT + "(3, {ndof}), got read-only"),
    ("Fortran out['jacobian']",
     lambda s: s.group("force_jacobian")({"e": s.batch, "e0": s.e0s(1)},
                                         {"jacobian": fortran(3, s.ndof**2)}),
     "out['jacobian']: " + OUT + "(3, {ndof2}), got Fortran-ordered"),
    ("float32 out['energy']",
     lambda s: s.group("energy")({"e": s.batch, "e0": s.e0s(1)},
                                 {"energy": np.zeros((3, 1), np.float32)}),
     "out['energy']: " + OUT + "(3, 1), got float32"),
    ("out['force'] with too few rows",
     lambda s: s.group()({"e": s.batch, "e0": s.e0s(1)}, {"force": np.zeros((2, s.ndof))}),
     "out['force']: " + OUT + "(3, {ndof}), got float64 array of shape (2, {ndof})"),
    ("unknown kernel", lambda s: s.group("forces"),
     "kernel: expected one of energy, force, force_jacobian for {kind}"),
    ("one-shot: e of the wrong width",
     lambda s: s.one_shot("force", e=np.zeros((1, 10)), e0=s.e0s(1)),
     "e: " + WIDTH_24 + "(1, 10)"),
    ("one-shot: e0 with fewer rows than e",
     lambda s: s.one_shot("force", e=s.batch, e0=s.e0s(2)),
     "e: expected shape (2, {ndof}) or (1, {ndof}) float64 for {kind}"),
    ("one-shot: float32 e0 of the wrong width",
     lambda s: s.one_shot("force", e=s.batch, e0=np.zeros((1, 3), np.float32)),
     "e0: " + WIDTH_24 + "(1, 3)"),
    ("one-shot: gram of the wrong size",
     lambda s: s.one_shot("energy", e=s.batch, e0=s.e0s(1), gram=np.zeros(5)),
     "gram: expected shape ("),
    ("one-shot: missing gram",
     lambda s: s.one_shot("energy", e=s.batch, e0=s.e0s(1), gram=None),
     "gram: missing input of the energy kernel of {kind} (gram_straight)"),
    ("one-shot: missing e", lambda s: s.one_shot("energy", e0=s.e0s(1)),
     "e: missing; the energy kernel for {kind} takes e"),
    ("one-shot: inputs not a dict",
     lambda s: kernel_family(s.kind, s.el.family, s.backend)("force", [s.batch]),
     "inputs: expected a dict"),
    ("one-shot: read-only out",
     lambda s: s.one_shot("energy", {"energy": readonly(3, 1)}, e=s.batch, e0=s.e0s(1)),
     "out['energy']: " + OUT + "(3, 1), got read-only"),
]


# --- 4: coordinates e of the public methods ---------------------------------------------------

E_REAL = ("e: expected real numbers (float or integer), shape ({ndof},) or (m, {ndof}) for "
          "{kind}, got ")
E_SHAPE = "e: expected shape ({ndof},) or (m, {ndof}) for {kind}, got "

BAD_COORDINATES = [  # (description, bad e from the Setup, fragment)
    ("complex", lambda s: s.e + 1e-3j, E_REAL + "complex128 array of shape ({ndof},)"),
    ("complex, zero imaginary part", lambda s: s.batch.astype(complex),
     E_REAL + "complex128 array of shape (3, {ndof})"),
    ("object array", lambda s: np.array(list(s.e), dtype=object), E_REAL + "object array"),
    ("list holding None", lambda s: [None] * s.ndof, E_REAL + "object values"),
    ("None", lambda s: None, E_REAL + "object values"),
    ("strings", lambda s: [str(x) for x in s.e], E_REAL + "<U"),
    ("ragged nested list", lambda s: [list(s.e), [1.0, 2.0]],
     "e: expected real numbers, shape ({ndof},) or (m, {ndof}) for {kind}; "),
    ("bool array", lambda s: np.ones(s.ndof, bool), E_REAL + "bool array"),
    ("NaN", lambda s: np.where(np.arange(s.ndof) == 3, np.nan, s.e), "e: contains NaN"),
    ("inf in a batch", lambda s: np.where(np.arange(s.ndof) == 3, np.inf, s.batch),
     "e: contains NaN or infinite"),
    ("3-D array", lambda s: s.batch[None], E_SHAPE + "(1, 3, {ndof})"),
    ("scalar", lambda s: 1.0, E_SHAPE + "()"),
    ("empty list", lambda s: [], E_SHAPE + "(0,)"),
    ("one coordinate short", lambda s: s.e[:-1], E_SHAPE + "("),
]

PUBLIC_METHODS = ["elastic_force", "elastic_jacobian", "strain_energy",
                  "elastic_force_and_jacobian"]

COORDINATE_CASES = [
    (f"{method}: {description}",
     lambda s, method=method, value=value: getattr(s.el, method)(value(s)), fragment)
    for method in PUBLIC_METHODS for description, value, fragment in BAD_COORDINATES
]


# --- 5: constructor arguments -----------------------------------------------------------------

POSITIVE = ": expected a positive finite number between 1e-30 and 1e+30, got "
NU_RANGE = "nu: expected Poisson's ratio in (-1, 0.5), got "
ORDERS = "quadrature: expected {dim} Gauss orders between 1 and 64"
E0_REAL = "e0: expected real numbers (float or integer), shape ({ndof},) for {kind}, got "


def overflow_scale(dim: int) -> float:
    """A factor s on e0 that overflows the invariants: det J0 grows as s**dim, so U0 (about
    E V s**dim) and the mass pass float64's maximum.  s**dim = 1e-4 times that maximum keeps
    s**dim itself (det J0, the reference check) finite while E V (~1e9 here) overflows U0."""
    return float((np.finfo(float).max * 1e-4) ** (1 / dim))


CONSTRUCTOR_CASES = [
    ("length as a string", lambda s: s.make(length="1"), "length" + POSITIVE + "'1'"),
    ("length True", lambda s: s.make(length=True), "length" + POSITIVE + "True"),
    ("length np.bool_", lambda s: s.make(length=np.bool_(True)), "length" + POSITIVE),
    ("length None", lambda s: s.make(length=None), "length" + POSITIVE + "None"),
    ("length NaN", lambda s: s.make(length=np.nan), "length" + POSITIVE + "nan"),
    ("length inf", lambda s: s.make(length=np.inf), "length" + POSITIVE + "inf"),
    ("length negative", lambda s: s.make(length=-1.0), "length" + POSITIVE + "-1.0"),
    ("length zero", lambda s: s.make(length=0), "length" + POSITIVE + "0"),
    ("length huge", lambda s: s.make(length=1e200), "length" + POSITIVE + "1e+200"),
    ("length tiny", lambda s: s.make(length=1e-200), "length" + POSITIVE + "1e-200"),
    ("length int beyond float", lambda s: s.make(length=10**400), "length" + POSITIVE),
    ("length complex", lambda s: s.make(length=1 + 0j), "length" + POSITIVE + "(1+0j)"),
    ("length an array", lambda s: s.make(length=np.array([1.0])), "length" + POSITIVE),
    ("height as a string", lambda s: s.make(height="0.1"), "height" + POSITIVE + "'0.1'"),
    ("height huge", lambda s: s.make(height=1e60), "height" + POSITIVE + "1e+60"),
    ("width NaN", lambda s: s.make(width=float("nan")), "width" + POSITIVE + "nan"),
    ("width False", lambda s: s.make(width=False), "width" + POSITIVE + "False"),
    ("E as a string", lambda s: s.make(E="2.1e11"), "E" + POSITIVE + "'2.1e11'"),
    ("E overflowing the invariants", lambda s: s.make(E=1e308), "E" + POSITIVE + "1e+308"),
    ("E inf", lambda s: s.make(E=np.inf), "E" + POSITIVE + "inf"),
    ("rho huge", lambda s: s.make(rho=1e308), "rho" + POSITIVE + "1e+308"),
    ("rho subnormal", lambda s: s.make(rho=1e-320), "rho" + POSITIVE),
    ("rho as a string", lambda s: s.make(rho="7800"), "rho" + POSITIVE + "'7800'"),
    ("nu as a string", lambda s: s.make(nu="0.3"), NU_RANGE + "'0.3'"),
    ("nu True", lambda s: s.make(nu=True), NU_RANGE + "True"),
    ("nu None", lambda s: s.make(nu=None), NU_RANGE + "None"),
    ("nu NaN", lambda s: s.make(nu=np.nan), NU_RANGE + "nan"),
    ("nu inf", lambda s: s.make(nu=-np.inf), NU_RANGE + "-inf"),
    ("nu 0.5", lambda s: s.make(nu=0.5), NU_RANGE + "0.5"),
    ("nu int beyond float", lambda s: s.make(nu=10**400), NU_RANGE),
    ("kind a number", lambda s: s.make(kind=3), "kind: expected an element kind name"),
    ("kind a list", lambda s: s.make(kind=[s.kind]), "kind: expected an element kind name"),
    ("kind None", lambda s: s.make(kind=None), "kind: expected an element kind name"),
    ("kind unknown", lambda s: s.make(kind="plate9"), "kind: unknown element kind 'plate9'"),
    ("method None", lambda s: s.make(method=None), "method: expected one of"),
    ("method a list", lambda s: s.make(method=["gram"]), "method: expected one of"),
    ("method an array", lambda s: s.make(method=np.array(["gram"])), "method: expected one of"),
    ("method misspelt", lambda s: s.make(method="Gram"), "method: expected one of"),
    ("backend a list", lambda s: s.make(backend=["c"]), "backend: expected one of"),
    ("backend None", lambda s: s.make(backend=None), "backend: expected one of"),
    ("quadrature a string", lambda s: s.make(quadrature="533"), ORDERS),
    ("quadrature floats", lambda s: s.make(quadrature=(5.0,) + (3,) * (s.dim - 1)), ORDERS),
    ("quadrature bools", lambda s: s.make(quadrature=(True,) * s.dim), ORDERS),
    ("quadrature a scalar", lambda s: s.make(quadrature=5), ORDERS),
    ("quadrature a set", lambda s: s.make(quadrature={5, 3, 2}), ORDERS),
    ("quadrature too few", lambda s: s.make(quadrature=(5,)), ORDERS),
    ("quadrature order 0", lambda s: s.make(quadrature=(0,) * s.dim), ORDERS),
    ("e0 with NaN", lambda s: s.make(e0=np.where(np.arange(s.ndof) == 4, np.nan, s.el.e0)),
     "e0: contains NaN or infinite values"),
    ("e0 with inf", lambda s: s.make(e0=s.el.e0 * np.inf), "e0: contains NaN or infinite"),
    ("e0 too short", lambda s: s.make(e0=np.zeros(5)),
     "e0: expected shape ({ndof},) for {kind}, got (5,)"),
    ("e0 a batch", lambda s: s.make(e0=s.e0s(2)),
     "e0: expected shape ({ndof},) for {kind}, got (2, {ndof})"),
    ("e0 complex", lambda s: s.make(e0=s.el.e0 + 0j), E0_REAL + "complex128 array"),
    ("e0 bool", lambda s: s.make(e0=s.el.e0 > 0), E0_REAL + "bool array"),
    ("e0 strings", lambda s: s.make(e0=[str(x) for x in s.el.e0]), E0_REAL + "<U"),
    ("e0 a string", lambda s: s.make(e0="abc"), E0_REAL + "<U3 values"),
    ("e0 with None", lambda s: s.make(e0=[None] * s.ndof), E0_REAL + "object values"),
    ("e0 degenerate (r_y = 0; plates r_z)", lambda s: s.make(e0=degenerate_reference(s.kind)),
     "e0: the reference mapping is degenerate or inverted"),
    ("e0 overflowing the invariants", lambda s: s.make(e0=s.el.e0 * overflow_scale(s.dim)),
     "length, height, width, E, nu, rho, e0: the invariants overflow float64"),
]

ALL_CASES = ELEMENT_OUT_CASES + GROUP_CASES + COORDINATE_CASES + CONSTRUCTOR_CASES

#: A kind whose energy takes straight references only (cables, element.json ``energy``)
#: refuses these non-rigid references before their mapping or invariants are formed.
STRAIGHT_ONLY = {"e0 degenerate (r_y = 0; plates r_z)": "e0: {kind} takes straight references "
                 "only", "e0 overflowing the invariants": "e0: {kind} takes straight references "
                 "only"}


def expected(kind: str, description: str, fragment: str) -> str:
    """The fragment case ``description`` expects for ``kind`` (``STRAIGHT_ONLY``)."""
    if element_kind(kind).energy.curved is not None:
        return STRAIGHT_ONLY.get(description, fragment)
    return fragment


def case_ids(cases) -> list[str]:
    return [description for description, _, _ in cases]


def test_corpus_descriptions_are_unique():
    assert len(set(case_ids(ALL_CASES))) == len(ALL_CASES)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # overflow while forming invariants
@pytest.mark.parametrize("description, call, fragment", ALL_CASES, ids=case_ids(ALL_CASES))
def test_bad_call_raises_value_error_naming_the_argument(setup, description, call, fragment):
    raises(setup, call, expected(setup.kind, description, fragment))


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("description, call, fragment", ALL_CASES, ids=case_ids(ALL_CASES))
def test_backends_give_identical_messages(kind, description, call, fragment):
    c, numpy = (raises(Setup(kind, backend), call, expected(kind, description, fragment))
                for backend in BACKENDS)
    assert c == numpy


def test_rejected_out_is_left_untouched(setup):
    """No partial write into a buffer that was refused."""
    out = np.full((3, setup.ndof, setup.ndof), 7.0, order="F")
    with pytest.raises(ValueError, match="out: "):
        setup.el.elastic_jacobian(setup.batch, out=out)
    assert (out == 7.0).all()


# --- what is accepted: conversions, empty batches, NumPy scalars ------------------------------

CONVERTED_INPUTS = [  # (description, e batch from a float64 (m, ndof) batch): same values
    ("float32", lambda b: b.astype(np.float32)),
    ("big-endian float64", lambda b: b.astype(">f8")),
    ("Fortran-ordered", lambda b: np.asfortranarray(b)),
    ("non-contiguous rows", lambda b: np.repeat(b, 2, axis=0)[::2]),
    ("non-contiguous columns", lambda b: np.repeat(b, 2, axis=1)[:, ::2]),
    ("integers", lambda b: np.round(b * 1000).astype(np.int64)),
    ("nested lists", lambda b: b.tolist()),
]


@pytest.mark.parametrize("description, convert", CONVERTED_INPUTS,
                         ids=[d for d, _ in CONVERTED_INPUTS])
def test_group_kernel_converts_real_inputs_never_reinterprets(setup, description, convert):
    """Real inputs of another dtype or layout give the results of their float64 values."""
    kernel = setup.group("force_jacobian")
    e, e0 = convert(setup.batch), convert(setup.e0s(3))
    values = {"e": np.array(e, dtype=np.float64), "e0": np.array(e0, dtype=np.float64)}
    expected = kernel(values)
    result = kernel({"e": e, "e0": e0})
    for name in ("force", "jacobian"):
        assert np.isfinite(result[name]).all()
        np.testing.assert_array_equal(result[name], expected[name])
    force = kernel({"e": values["e"], "e0": setup.e0s(1)})["force"]
    np.testing.assert_array_equal(setup.el.elastic_force(e), force)


def test_group_kernel_fills_valid_out_and_broadcasts_one_e0(setup):
    kernel = setup.group("force_jacobian")
    out = {"force": np.full((3, setup.ndof), np.nan),
           "jacobian": np.full((3, setup.ndof**2), np.nan)}
    result = kernel({"e": setup.batch, "e0": setup.e0s(1)}, out)
    assert result["force"] is out["force"] and result["jacobian"] is out["jacobian"]
    tiled = kernel({"e": setup.batch, "e0": setup.e0s(3)})
    np.testing.assert_array_equal(out["force"], tiled["force"])
    np.testing.assert_array_equal(out["jacobian"], tiled["jacobian"])
    np.testing.assert_array_equal(out["force"], setup.el.elastic_force(setup.batch))


def test_one_e_shared_by_a_batch_of_references(setup):
    """e (1, ndof) with e0 (m, ndof): the row of e is used for every element, in both
    backends (the NumPy kernels used to take m from e)."""
    e0s = np.stack([setup.el.e0, setup.el.e0 + 1e-3, setup.el.e0 - 1e-3])
    shared = setup.group()({"e": setup.batch[:1], "e0": e0s})["force"]
    tiled = setup.group()({"e": np.repeat(setup.batch[:1], 3, axis=0), "e0": e0s})["force"]
    np.testing.assert_array_equal(shared, tiled)


def test_empty_batch_gives_empty_results(setup):
    el, ndof = setup.el, setup.ndof
    empty = np.zeros((0, ndof))
    assert el.elastic_force(empty).shape == (0, ndof)
    assert el.elastic_jacobian(empty).shape == (0, ndof, ndof)
    assert el.strain_energy(empty).shape == (0,)
    force, jacobian = el.elastic_force_and_jacobian(empty, out_force=np.zeros((0, ndof)))
    assert force.shape == (0, ndof) and jacobian.shape == (0, ndof, ndof)
    result = setup.group("force_jacobian")({"e": empty, "e0": setup.e0s(1)})
    assert result["force"].shape == (0, ndof) and result["jacobian"].shape == (0, ndof**2)


def test_numpy_scalars_are_accepted(setup):
    """NumPy scalars (and exact integers) give the element plain Python numbers give; e0 in
    float32 too (sides exact in float32, so are the node positions of the straight e0)."""
    sides = (1.0, 0.125, 0.0625)
    e0 = element_kind(setup.kind).straight_reference(*sides).astype(np.float32)
    el = Element(np.str_(setup.kind), *map(np.float64, sides), np.int64(E_MODULUS),
                 np.float32(0.25), np.float64(RHO), e0=e0, method=np.str_("gram"),
                 backend=np.str_(setup.backend), quadrature=np.array(setup.el.quadrature))
    plain = Element(setup.kind, *sides, E_MODULUS, 0.25, RHO, backend=setup.backend)
    np.testing.assert_array_equal(el.elastic_force(setup.batch), plain.elastic_force(setup.batch))
    np.testing.assert_array_equal(el.mass_matrix(), plain.mass_matrix())
