"""Agreement with Project Chrono's ChElementBeamANCF_3243 (ECM law, Kelvin-Voigt damping).

Chrono's unit test (src/tests/unit_tests/fea/utest_FEA_ANCFbeam_3243_Formulation.cpp) checks
one element against reference files kept in ../shared/refdata/chrono_3243/.  Its setup:
L = 1 m, a 0.1 x 0.1 m section, rho = 7850 kg/m^3, E = 210 GPa, nu = 0.3,
k1 = k2 = 10 (1 + nu) / (12 + 11 nu), straight along x from the origin with unit slopes;
"small displacement" puts node B at z = 0.001 m, "small velocity" gives node B a z velocity of
0.001 m/s, and the damped cases use alpha = 0.01 s.  Conventions, from Chrono's sources:

* the mass matrix file is the 8 x 8 shape-level matrix (times I_3 it is the element's);
* the gravity file is the generalised gravity force for g = (0, 0, -9.80665) m/s^2;
* internal forces have the sign of our elastic (plus damping) force;
* Jacobian files hold K = -d(force)/de (24 rows), and the damped ones stack R =
  -d(force)/d(e_dot) below it (48 rows), force being the elastic plus damping force.

Every entry must agree to 1e-9 relative; entries that are zero in Chrono's files must be at
most 1e-12 of the file's largest entry here.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from runtime import Element

REFDATA = Path(__file__).resolve().parents[1].parent / "shared" / "refdata" / "chrono_3243"
ALPHA = 0.01
GRAVITY = np.array([0.0, 0.0, -9.80665])
NODE_B_Z = 14  # coordinate index of node B's z position (node-major r, r_x, r_y, r_z)

pytestmark = pytest.mark.skipif(
    not REFDATA.is_dir(),
    reason=f"Project Chrono's ANCF 3243 reference files are not in {REFDATA} (they live in the "
           "shared folder beside the repository, ../shared/refdata/chrono_3243)")


def reference(name: str) -> np.ndarray:
    return np.loadtxt(REFDATA / f"UT_ANCFBeam_3243_{name}.txt")


@functools.cache
def chrono_element(method: str, backend: str) -> Element:
    return Element("beam3d", 1.0, 0.1, 0.1, 210e9, 0.3, 7850.0, method=method, backend=backend,
                   law="ecm", damping=ALPHA)


def small() -> np.ndarray:
    """Node B's z (a position offset or a velocity) at 0.001, everything else zero."""
    out = np.zeros(24)
    out[NODE_B_Z] = 1e-3
    return out


def computed(el: Element, name: str) -> np.ndarray:
    """The quantity of Chrono's file ``name`` from our element."""
    e0, rest = el.e0, np.zeros(el.ndof)
    displaced = e0 + small()
    if name == "MassMatrix":
        return el.mass_matrix()[::3, ::3]
    if name == "Grav":  # consistent gravity force: M times a uniform translation by g
        translation = np.zeros(el.ndof)
        translation[0:3] = translation[12:15] = GRAVITY
        return el.mass_matrix() @ translation
    if name == "IntFrcSmallDispNoVel":
        return el.elastic_force(displaced)
    if name == "IntFrcNoDispSmallVel":
        return el.internal_force_and_jacobians(e0, small())[0]
    if name.endswith("NoDamping"):
        e = displaced if "SmallDisp" in name else e0
        return -el.elastic_jacobian(e)
    e = displaced if "SmallDisp" in name else e0
    e_dot = small() if "SmallVel" in name else rest
    _, de, de_dot = el.internal_force_and_jacobians(e, e_dot)
    return np.vstack([-de, -de_dot])


FILES = ["MassMatrix", "Grav", "IntFrcSmallDispNoVel", "IntFrcNoDispSmallVel",
         "JacNoDispNoVelNoDamping", "JacSmallDispNoVelNoDamping", "JacNoDispNoVelWithDamping",
         "JacSmallDispNoVelWithDamping", "JacNoDispSmallVelWithDamping"]


def errors(ours: np.ndarray, theirs: np.ndarray) -> tuple[float, float]:
    """(max relative error over Chrono's nonzero entries, max |ours| over its zero entries
    relative to its largest entry)."""
    nonzero = theirs != 0
    relative = np.abs(ours[nonzero] - theirs[nonzero]) / np.abs(theirs[nonzero])
    zeros = np.abs(ours[~nonzero]).max(initial=0.0) / np.abs(theirs).max()
    return float(relative.max()), float(zeros)


@pytest.mark.parametrize("name", FILES)
@pytest.mark.parametrize("method", ["gram", "cij", "quadrature"])
@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_matches_chrono_reference(name, method, backend):
    theirs = reference(name)
    ours = computed(chrono_element(method, backend), name)
    assert ours.shape == theirs.shape
    relative, zeros = errors(ours, theirs)
    # (cij forms K(e) e, |K| |e| ~ 3e9 N, so its smallest force entries, 242 N at the small
    # displacement, carry ~5e-10 relative rounding: within 1e-9, the closest margin here)
    assert relative <= 1e-9, f"{name}: max relative error {relative:.2e}"
    assert zeros <= 1e-12, f"{name}: entries Chrono has as zero reach {zeros:.2e} of the max"


def test_chrono_setup_uses_the_default_shear_correction():
    el = chrono_element("gram", "numpy")
    nu = 0.3
    assert el.shear_correction == pytest.approx((10 * (1 + nu) / (12 + 11 * nu),) * 2, rel=1e-15)
