"""What the stability study runs: the row every case reports (``Row``) and the groups of
rows, the problems of each group (kernel scenarios, the slender beam of the integrators,
Newton's large-deflection cantilever, the Poisson and Chrono cantilevers) with the scenes
they are built from, and the keyword arguments of every case (``cases``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

from runtime.catalog import INTEGRATORS, METHODS, material_laws
from runtime.kernels.kind import element_kind
from runtime.model.bodies import Body, Material
from runtime.model.items.constraints import Clamp
from runtime.model.items.loads import PointForce
from runtime.model.scene import Scene


@dataclass
class Row:
    """One measured case.

    measured: the key number (relative error, energy drift, convergence order, step in s...);
    tolerance: the stated bound it is compared with (``compare`` says how), None when the row
    is informational; passed: True / False, None when informational; detail: the other
    numbers; cause: why a row fails (or what an informational row shows).
    """

    group: str
    case: str
    method: str
    measured: float
    tolerance: float | None
    passed: bool | None
    detail: str
    cause: str
    compare: str = "<="   # "<=": measured <= tolerance; ">=": at least; "|x| <=": magnitude


def row_record(**values) -> dict:
    """A ``Row`` of ``values`` as a plain dict (what case functions return)."""
    return asdict(Row(**values))


GROUPS = {
    "kernel_accuracy": "Kernel accuracy against the 50-digit mpmath reference",
    "integrator": "Integrators on a stiff slender beam (trapezoidal vs generalized-alpha)",
    "newton": "Newton convergence on a large-deflection cantilever",
    "poisson_locking": "Poisson locking of the fully parameterised beam2d: svk locks, ecm "
                       "is the remedy",
    "chrono_beam": "Project Chrono's 20-element aluminium beam3d (nu = 0.33) against closed "
                   "forms, svk and ecm",
}

# --------------------------------------------------------------------------- kernel accuracy

@dataclass(frozen=True)
class Scenario:
    """An element and a configuration: sizes in m, E in Pa; ``strain`` the size of the random
    perturbation (positions scaled by the length); ``offset`` (m) added to every position
    coordinate of the reference and the configuration; ``rotation`` in rad (0: none)."""

    strain: float = 1e-6
    offset: float = 0.0
    rotation: float = 0.0
    length: float = 1.0
    height: float = 0.1
    width: float = 0.05
    E: float = 2.1e11
    nu: float = 0.3
    rho: float = 7800.0


SCENARIOS = {
    "strain_1e-3": Scenario(strain=1e-3),
    "strain_1e-6": Scenario(strain=1e-6),
    "strain_1e-9": Scenario(strain=1e-9),
    "offset_1e3": Scenario(offset=1e3),
    "offset_1e6": Scenario(offset=1e6),
    "large_rotation": Scenario(strain=1e-3, rotation=2.9),
    "large_rotation_strain_1e-6": Scenario(strain=1e-6, rotation=2.9),
    "stiff_E1e13": Scenario(E=1e13),
    "soft_E1e6": Scenario(E=1e6),
    "slender_1e2": Scenario(height=1e-2, width=1e-2),
    "slender_1e3": Scenario(height=1e-3, width=1e-3),
    "slender_1e4": Scenario(height=1e-4, width=1e-4),
    "nu_0.49": Scenario(nu=0.49),
}


# --------------------------------------------------------------------------- integrators

#: The slender beam2d of the integrator rows: L = 1 m, h = 2 mm, w = 10 mm, steel, nu = 0
#: (no Poisson locking), clamped at x = 0, 4 elements; released from the static deflection
#: under a tip load of 0.3 E I / L^3 (about 5.5 % of L).
SLENDER = {"length": 1.0, "height": 2e-3, "width": 1e-2, "E": 2.1e11, "nu": 0.0,
           "rho": 7800.0, "elements": 4}
T_END = 1.2        # s, about two periods of the first bending mode (0.59 s)
STEPS = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 1e-1)
COMMON_STEP = 1e-3
#: (integrator, rho_inf) of the scan: every integrator at rho_inf = 0.8 (the trapezoidal rule
#: has no parameter), and generalized-alpha also at 0.5
INTEGRATOR_VARIANTS = (*((name, 0.8) for name in INTEGRATORS), ("generalized_alpha", 0.5))


def cantilever_scene(element: str, material: Material, elements: int, length: float,
                     height: float, width: float, loads: Sequence = (), title: str = "") -> Scene:
    """A cantilever of the study along +x from the origin, clamped at node 0 (the body is
    ``beam``, so loads refer to ``beam:-1``)."""
    origin = (0.0,) * (2 if element == "beam2d" else 3)
    end = (length,) + origin[1:]
    return Scene(title=title or "stability study cantilever", materials=[material],
                 bodies=[Body("beam", element, material.name, height, width, elements,
                              origin, end)],
                 constraints=[Clamp("beam:0")], loads=list(loads))


def slender_scene(tip_load: float = 0.0) -> Scene:
    """The slender cantilever of the integrator rows (``tip_load`` in N, -y at the tip)."""
    p = SLENDER
    loads = [PointForce("beam:-1", (0.0, -tip_load))] if tip_load else []
    return cantilever_scene("beam2d", Material("steel", E=p["E"], nu=p["nu"], rho=p["rho"]),
                            p["elements"], p["length"], p["height"], p["width"], loads,
                            "slender beam2d (stability study)")


# --------------------------------------------------------------------------- Newton

#: The paper's cantilever section (L = 5 m, 0.1 x 0.1 m, E = 132 GPa, nu = 0), 4 beam3d
#: elements, with a tip load of 20 kN (67 times the paper's): tip deflection ~0.68 m.
NEWTON = {"length": 5.0, "height": 0.1, "width": 0.1, "E": 132e9, "nu": 0.0, "rho": 8245.2,
          "elements": 4, "load": 2e4}

# --------------------------------------------------------------------------- Poisson locking

POISSON = {"length": 2.0, "height": 0.5, "width": 0.1, "E": 2.07e11, "load": 62500.0,
           "reference": 8.099e-4}
POISSON_ELEMENTS = (2, 4, 8, 16, 32)

#: Project Chrono's ANCF-3243 unit-test beam (utest_FEA_ANCFbeam_3243_Formulation): aluminium
#: 7075, 20 elements, 20 in long; section 0.125 x 0.5 in (tip load, axial) or 0.5 x 0.125 in
#: (gravity, bending about the thin side)
INCH = 0.0254
CHRONO_BEAM = {"E": 71.7e9, "nu": 0.33, "rho": 2810.0, "length": 20 * INCH,
               "elements": 20, "thin": 0.125 * INCH, "wide": 0.5 * INCH, "g": 9.80665}


# --------------------------------------------------------------------------- the cases

def cases(quick: bool = False) -> list[dict]:
    """Keyword arguments of every ``run_case`` call, longest first (better load balance)."""
    if quick:
        return [
            {"study": "kernel", "scenario": "strain_1e-9", "method": "gram"},
            {"study": "kernel", "scenario": "offset_1e6", "method": "gram"},
            {"study": "newton", "jacobian": "analytic"},
            {"study": "poisson", "nu": 0.3, "elements": 4},
            {"study": "poisson", "nu": 0.3, "elements": 4, "law": "ecm"},
            {"study": "chrono_beam", "law": "ecm", "load": "tip"},
            {"study": "integrator", "integrator": "trapezoidal", "step": 2e-3},
            {"study": "integrator", "integrator": "trapezoidal", "step": 2e-2},
        ]
    out = []
    for step in STEPS:   # small steps first: they take longest
        for integrator, rho in INTEGRATOR_VARIANTS:
            out.append({"study": "integrator", "integrator": integrator, "step": step,
                        "rho_inf": rho})
    for integrator, rho in INTEGRATOR_VARIANTS:   # diagnostics: more Newton iterations
        for step in (1e-2, 1e-1) if rho > 0.5 else (1e-1,):
            out.append({"study": "integrator", "integrator": integrator, "step": step,
                        "rho_inf": rho, "max_iterations": 200})
    out += [{"study": "kernel", "scenario": s, "method": m} for s in SCENARIOS for m in METHODS]
    out += [{"study": "newton", "jacobian": "analytic"},
            {"study": "newton", "jacobian": "finite_difference"},
            {"study": "newton", "jacobian": "finite_difference", "scheme": "forward",
             "relative_step": 1e-4}]
    # every law of the beams the locking rows run (beam2d, beam3d): the cables' and shells'
    # laws do not apply to them
    out += [{"study": "poisson", "nu": nu, "elements": n, "law": law}
            for law in beam_laws("beam2d") for nu in (0.3, 0.0) for n in POISSON_ELEMENTS]
    out += [{"study": "chrono_beam", "law": law, "load": load}
            for law in beam_laws("beam3d") for load in ("axial", "tip", "gravity")]
    return out


def beam_laws(kind: str) -> tuple[str, ...]:
    """The material laws of ``kind`` in the catalog's order (the default first)."""
    return tuple(law for law in material_laws() if law in element_kind(kind).laws)
