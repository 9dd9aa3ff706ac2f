"""Kernel accuracy rows: force and strain energy of a method (C backend) at the scenarios
of ``plan.SCENARIOS`` against the 50-digit mpmath reference of
``runtime.studies.highprecision``, with the rounding estimate that explains cij's errors.
"""

from __future__ import annotations

import functools
import math
import zlib

import numpy as np

from runtime.catalog import generated_kinds
from runtime.kernels.kind import element_kind
from runtime.studies.stability.plan import SCENARIOS, Scenario, row_record

EPS = float(np.finfo(float).eps)

KERNEL_TOLERANCE = 1e-6
EXPLAINED = 100   # a cij error within 100 times its rounding estimate is explained by it
KINDS = tuple(generated_kinds())   # every generated element kind
GRID = 2.0**-33   # positions rounded to it: x + 1e6 is exact for |x| < 2**20 - 1e6


def _describe(s: Scenario) -> str:
    parts = [f"perturbation {s.strain:g}"]
    if s.offset:
        parts.append(f"reference and configuration {s.offset:g} m from the origin")
    if s.rotation:
        parts.append(f"rotated {s.rotation:g} rad")
    parts.append(f"L/h {s.length / s.height:g}, E {s.E:g} Pa, nu {s.nu:g}")
    return ", ".join(parts)


def _rotation(dim: int, angle: float) -> np.ndarray:
    """A rotation by ``angle`` (rad): about z in 2D, about the axis (1, 2, 3) in 3D."""
    c, s = math.cos(angle), math.sin(angle)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    axis = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return c * np.eye(3) + s * cross + (1 - c) * np.outer(axis, axis)


@functools.cache
def kernel_configuration(kind: str, scenario: str) -> dict:
    """Reference and configuration of ``scenario`` and their 50-digit (U, force).

    Returns e0 and e as given to the kernels (placed at the offset) and the mpmath energy (J)
    and force (N).  With an offset, positions are first rounded to a 2**-33 grid so that the
    placed pair is exactly the unplaced one moved (the reference is computed unplaced).
    """
    from runtime.studies import highprecision

    s = SCENARIOS[scenario]
    info = element_kind(kind)
    d, n = info.dim, info.n_shape
    positions = list(info.position_vectors)
    rng = np.random.default_rng(zlib.crc32(f"{kind}/{scenario}".encode()))
    noise = rng.standard_normal((n, d))
    noise[positions] *= s.length
    rotation = _rotation(d, s.rotation)
    q0 = info.straight_reference(s.length, s.height, s.width).reshape(n, d) @ rotation.T
    q = q0 + s.strain * noise @ rotation.T
    if s.offset:
        q0[positions] = np.round(q0[positions] / GRID) * GRID
        q[positions] = np.round(q[positions] / GRID) * GRID
    energy, force = highprecision.energy_and_force(kind, q.ravel(), q0.ravel(), s.length,
                                                   s.height, s.width, s.E, s.nu)
    placed0, placed = q0.copy(), q.copy()
    placed0[positions] += s.offset
    placed[positions] += s.offset
    back0, back = placed0.copy(), placed.copy()
    back0[positions] -= s.offset
    back[positions] -= s.offset
    if not (np.array_equal(back0, q0) and np.array_equal(back, q)):
        raise AssertionError(f"{scenario}: the offset configuration is not exactly representable")
    return {"e0": placed0.ravel(), "e": placed.ravel(), "energy": energy, "force": force}


def _u0(kind: str, s: Scenario) -> float:
    """U0 of eqs. 40-41 (J): the energy at e = 0, where E = -I/2 (tr E = -dim/2, E:E = dim/4):
    (lam dim^2/8 + G dim/4) V, i.e. (9 lam + 6 G)/8 V in 3D, (lam + G)/2 V in 2D."""
    from runtime.studies import highprecision

    lam = s.E * s.nu / ((1 + s.nu) * (1 - 2 * s.nu))
    shear = s.E / (2 * (1 + s.nu))
    d = element_kind(kind).dim
    return (lam * d**2 / 8 + shear * d / 4) * highprecision.volume(kind, s.length, s.height,
                                                                  s.width)


def kernel_accuracy_case(scenario: str, method: str, kinds: tuple[str, ...] = KINDS) -> list[dict]:
    """Rows (force, energy) per element kind: relative errors of ``method`` (C backend)
    against the mpmath reference; tolerance 1e-6 for every row."""
    from runtime import Element

    s = SCENARIOS[scenario]
    rows = []
    for kind in kinds:
        config = kernel_configuration(kind, scenario)
        element = Element(kind, s.length, s.height, s.width, s.E, s.nu, s.rho, e0=config["e0"],
                          method=method, backend="c")
        force = element.elastic_force(config["e"])
        energy = element.strain_energy(config["e"])
        reference, ref_energy = config["force"], config["energy"]
        scale = float(np.abs(reference).max())
        force_error = float(np.abs(force - reference).max() / scale)
        energy_error = abs(energy - ref_energy) / abs(ref_energy)
        ratio = _u0(kind, s) / ref_energy
        common = (f"{_describe(s)}; U = {ref_energy:.3e} J (effective strain 0.5 sqrt(U/U0) "
                  f"= {0.5 / math.sqrt(ratio):.1e}), max|f| = {scale:.3e} N, U0/U = {ratio:.1e}")
        for quantity, error in (("force", force_error), ("energy", energy_error)):
            passed = bool(error <= KERNEL_TOLERANCE)
            if quantity == "force":
                expected = EPS * math.sqrt(ratio)
                formula = (f"cij forms K(e) e = K2(e) e + K1 e, terms ~sqrt(U0/U) times the "
                           f"force that cancel: rounding ~ eps sqrt(U0/U) = {expected:.1e}")
            else:
                expected = EPS * ratio
                formula = (f"cij energy by eq. 39, U = 1/4 e^T K2 e + 1/2 e^T K1 e + U0, adds "
                           f"terms of size U0 = {_u0(kind, s):.3e} J to U = {ref_energy:.3e} "
                           f"J: rounding ~ eps U0/U = {expected:.1e}")
            if passed:
                cause = ""
            elif method == "cij" and error <= EXPLAINED * expected:
                cause = formula
            elif method == "cij":
                cause = (f"unexplained: {error:.1e} is {error / expected:.0e} times the "
                         f"rounding estimate ({formula})")
            else:
                cause = (f"unexplained: {method} forms the strain first and should stay near "
                         f"eps; error {error:.1e}")
            detail = common + (f"; eps sqrt(U0/U) = {EPS * math.sqrt(ratio):.1e}"
                               if quantity == "force" else f"; eps U0/U = {EPS * ratio:.1e}")
            rows.append(row_record(group="kernel_accuracy", case=f"{scenario} {kind} {quantity}",
                             method=method, measured=error, tolerance=KERNEL_TOLERANCE,
                             passed=passed, detail=detail, cause=cause))
    return rows
