"""Agreement with Project Chrono's published ANCF unit-test data (ECM law for the beams,
Kelvin-Voigt damping).

Chrono's unit tests (src/tests/unit_tests/fea/utest_FEA_ANCF{beam_3243,beam_3333,shell_3443,
shell_3833, hexa_3843}_Formulation.cpp) check one element against reference files; copies are in
``tests/data/chrono/`` (BSD-3, with Chrono's licence).  Their setups:

* ANCF-3243 (``beam3d``) and ANCF-3333 (``beam3d_3node``): L = 1 m, a 0.1 x 0.1 m section,
  rho = 7850 kg/m^3, E = 210 GPa, nu = 0.3, k1 = k2 = 10 (1 + nu) / (12 + 11 nu) (the ECM law's
  default shear correction), straight along x from the origin with unit slopes.  Chrono's 3333
  orders its nodes A, B, C at x = 0, L, L/2; ours are at x = 0, L/2, L.
* ANCF-3443 (``plate3d``): a 1 x 1 m plate 0.01 m thick, rho = 7850 kg/m^3, E = 210 GPa,
  nu = 0.3 (Chrono's isotropic ChMaterialShellANCF: the full 3D St. Venant-Kirchhoff law),
  nodes at (0, 0), (L, 0), (L, W), (0, W).
* ANCF-3833 (``shell3d_3833``): the same plate, material and law (one layer of
  ChMaterialShellANCF at 0 degrees), eight nodes A, B, C, D at the corners, E, F, G, H at the
  mid-sides (our order), each carrying r, r_z = (0, 0, 1) and r_zz = 0.  Chrono's element
  integrates its force by a reduced 3 x 3 x 2 rule; its reference files are exact (MATLAB),
  as our closed forms and our 5 x 5 x 5 quadrature are.
* ANCF-3843 (``brick3d_3843``): a 1 x 1 x 1 m cube of the same material (Chrono's
  ChMaterialHexaANCF, the full 3D St. Venant-Kirchhoff law), corners A, B, C, D at z = 0 and
  E, F, G, H above them at z = 1 m (our order), each carrying r, r_x, r_y, r_z = the unit
  vectors.  Our straight invariants are an exact 7 x 7 x 7 Gauss rule at load time (its closed
  forms would be 34 MB), as are the quadrature method's.
* "small displacement" puts one node at z = 0.001 m, "small velocity" gives it a z velocity of
  0.001 m/s (node B of 3243, 3443, 3833 and 3843, the mid node C of 3333: in every case our
  node 1), and the damped cases use alpha = 0.01 s.

Conventions, from Chrono's sources: the mass matrix file is the shape-level matrix (times I_3 it
is the element's); the gravity file is the generalised gravity force for g = (0, 0, -9.80665)
m/s^2; internal forces have the sign of our elastic (plus damping) force; Jacobian files hold
K = -d(force)/de, and the damped ones stack R = -d(force)/d(e_dot) below it.

Every entry must agree to 1e-9 relative or to 1e-14 of the size of the sums it comes from (the
file's largest entry; for cij forces, formed as K(e) e, |K| |e|); entries that are zero in
Chrono's files must be at most 1e-12 of that size here.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from runtime import Element

DATA = Path(__file__).resolve().parent / "data" / "chrono"
ALPHA = 0.01
GRAVITY = np.array([0.0, 0.0, -9.80665])
MOVED_NODE = 1   # our index of the node Chrono displaces or moves


@dataclass(frozen=True)
class Case:
    """One Chrono element: our element's arguments and Chrono's node order."""

    chrono: str                      # Chrono's element number, e.g. "3243"
    prefix: str                      # file name prefix, e.g. "UT_ANCFBeam_3243"
    kind: str
    dimensions: tuple[float, float, float]
    law: str
    chrono_nodes: tuple[int, ...]    # our node index of Chrono's node 0, 1, ...

    def reference(self, name: str) -> np.ndarray:
        return np.loadtxt(DATA / f"chrono_{self.chrono}" / f"{self.prefix}_{name}.txt")


CASES = [
    Case("3243", "UT_ANCFBeam_3243", "beam3d", (1.0, 0.1, 0.1), "ecm", (0, 1)),
    Case("3333", "UT_ANCFBeam_3333", "beam3d_3node", (1.0, 0.1, 0.1), "ecm", (0, 2, 1)),
    Case("3443", "UT_ANCFShell_3443", "plate3d", (1.0, 1.0, 0.01), "svk", (0, 1, 2, 3)),
    Case("3833", "UT_ANCFShell_3833", "shell3d_3833", (1.0, 1.0, 0.01), "svk",
         tuple(range(8))),
    Case("3843", "UT_ANCFBrick_3843", "brick3d_3843", (1.0, 1.0, 1.0), "svk", tuple(range(8))),
]
#: Files of integrals of shape-function products only (no material, no state): tighter.
EXACT_FILES = ("MassMatrix", "Grav")
FILES = ["MassMatrix", "Grav", "IntFrcSmallDispNoVel", "IntFrcNoDispSmallVel",
         "JacNoDispNoVelNoDamping", "JacSmallDispNoVelNoDamping", "JacNoDispNoVelWithDamping",
         "JacSmallDispNoVelWithDamping", "JacNoDispSmallVelWithDamping"]


@functools.cache
def chrono_element(case: Case, method: str, backend: str) -> Element:
    return Element(case.kind, *case.dimensions, 210e9, 0.3, 7850.0, method=method,
                   backend=backend, law=case.law, damping=ALPHA)


def per_node(case: Case, el: Element) -> int:
    """Coordinates per node (nodes are node-major: r, then the gradients)."""
    return el.ndof // len(case.chrono_nodes)


def chrono_order(case: Case, el: Element) -> np.ndarray:
    """Our coordinate index of each of Chrono's coordinates (its nodes in its order)."""
    n = per_node(case, el)
    return np.concatenate([node * n + np.arange(n) for node in case.chrono_nodes])


def small(case: Case, el: Element) -> np.ndarray:
    """Our node 1's z (a position offset or a velocity) at 0.001, everything else zero."""
    out = np.zeros(el.ndof)
    out[MOVED_NODE * per_node(case, el) + 2] = 1e-3
    return out


def computed(case: Case, el: Element, name: str) -> np.ndarray:
    """The quantity of Chrono's file ``name`` from our element, in Chrono's coordinate order."""
    order = chrono_order(case, el)
    e0, rest = el.e0, np.zeros(el.ndof)
    displaced = e0 + small(case, el)
    if name == "MassMatrix":
        return el.mass_matrix()[np.ix_(order, order)][::3, ::3]
    if name == "Grav":  # consistent gravity force: M times a uniform translation by g
        translation = np.zeros(el.ndof)
        for node in range(len(case.chrono_nodes)):
            start = node * per_node(case, el)
            translation[start:start + 3] = GRAVITY
        return (el.mass_matrix() @ translation)[order]
    if name == "IntFrcSmallDispNoVel":
        return el.elastic_force(displaced)[order]
    if name == "IntFrcNoDispSmallVel":
        return el.internal_force_and_jacobians(e0, small(case, el))[0][order]
    e = displaced if "SmallDisp" in name else e0
    if name.endswith("NoDamping"):
        return -el.elastic_jacobian(e)[np.ix_(order, order)]
    e_dot = small(case, el) if "SmallVel" in name else rest
    _, de, de_dot = el.internal_force_and_jacobians(e, e_dot)
    return np.vstack([-de[np.ix_(order, order)], -de_dot[np.ix_(order, order)]])


def rounding_scale(case: Case, el: Element, name: str, method: str,
                   theirs: np.ndarray) -> float:
    """The size of the sums an entry comes from: the file's largest entry, except for cij
    forces, formed as K(e) e, whose terms are |K| |e| (much larger than the force)."""
    if method == "cij" and name.startswith("IntFrc"):
        return float(np.abs(el.elastic_jacobian(el.e0)).max() * np.abs(el.e0).max())
    return float(np.abs(theirs).max())


def errors(ours: np.ndarray, theirs: np.ndarray, scale: float) -> tuple[float, float]:
    """(max relative error over Chrono's nonzero entries, max |ours| over its zero entries
    relative to ``scale``).  An entry that differs by less than 1e-14 of ``scale``
    agrees to round-off whatever its relative error: some entries (5.8e-10 of the largest in
    the plate's Jacobian at the small displacement) are differences of terms of the
    largest's size, so neither Chrono's figures nor ours hold more relative digits there."""
    nonzero = theirs != 0
    difference = np.abs(ours[nonzero] - theirs[nonzero])
    relative = np.where(difference <= 1e-14 * scale, 0.0, difference / np.abs(theirs[nonzero]))
    zeros = np.abs(ours[~nonzero]).max(initial=0.0) / scale
    return float(relative.max()), float(zeros)


def test_reference_files_are_chronos():
    """The copies are byte-identical to Chrono's (the checksums Chrono's data came with)."""
    import hashlib
    for case in CASES:
        folder = DATA / f"chrono_{case.chrono}"
        for line in (folder / "SHA256SUMS").read_text().splitlines():
            digest, name = line.split()
            assert hashlib.sha256((folder / name).read_bytes()).hexdigest() == digest, name


@pytest.mark.parametrize("name", FILES)
@pytest.mark.parametrize("method", ["gram", "cij", "quadrature"])
@pytest.mark.parametrize("backend", ["c", "numpy"])
@pytest.mark.parametrize("case", CASES, ids=[c.chrono for c in CASES])
def test_matches_chrono_reference(case, name, method, backend):
    theirs = case.reference(name)
    if name == "Grav" or name.startswith("IntFrc"):
        theirs = theirs.ravel()
    el = chrono_element(case, method, backend)
    ours = computed(case, el, name)
    assert ours.shape == theirs.shape
    relative, zeros = errors(ours, theirs, rounding_scale(case, el, name, method, theirs))
    tolerance = 1e-12 if name in EXACT_FILES else 1e-9
    assert relative <= tolerance, f"{name}: max relative error {relative:.2e}"
    assert zeros <= 1e-12, f"{name}: entries Chrono has as zero reach {zeros:.2e} of the max"


def test_chrono_setup_uses_the_default_shear_correction():
    el = chrono_element(CASES[0], "gram", "numpy")
    nu = 0.3
    assert el.shear_correction == pytest.approx((10 * (1 + nu) / (12 + 11 * nu),) * 2, rel=1e-15)
