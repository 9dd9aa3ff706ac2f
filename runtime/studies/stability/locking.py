"""Static cantilever rows against closed forms, per material law: Poisson locking of the
beam2d (``plan.POISSON``, against shear-deformable beam theory) and Project Chrono's beam3d
(``plan.CHRONO_BEAM``, axial, tip and gravity loads).
"""

from __future__ import annotations

from runtime.model.bodies import Material
from runtime.model.items.loads import Gravity, PointForce
from runtime.model.settings import Static
from runtime.studies.stability.plan import CHRONO_BEAM, POISSON, cantilever_scene, row_record

POISSON_TOLERANCE = 0.01


def beam_theory(nu: float, shear_coefficient: float | None = None,
                bending_modulus: float | None = None) -> float:
    """Tip deflection (m) of the Poisson cantilever by shear-deformable beam theory:
    P L^3 / (3 E_b I) + P L / (k G A); k defaults to Cowper's 10 (1 + nu) / (12 + 11 nu),
    E_b to E."""
    p = POISSON
    area = p["height"] * p["width"]
    shear = p["E"] / (2 * (1 + nu))
    k = 10 * (1 + nu) / (12 + 11 * nu) if shear_coefficient is None else shear_coefficient
    return euler_bernoulli(bending_modulus) + p["load"] * p["length"] / (k * shear * area)


def euler_bernoulli(bending_modulus: float | None = None) -> float:
    """Tip deflection (m) of the Poisson cantilever without shear: P L^3 / (3 E_b I), E_b
    defaulting to E; the reference of the ``elastic_line`` law (a centre-line energy: no
    shear deflection)."""
    p = POISSON
    modulus = p["E"] if bending_modulus is None else bending_modulus
    return p["load"] * p["length"] ** 3 / (3 * modulus * p["width"] * p["height"] ** 3 / 12)


def poisson_case(nu: float, elements: int, law: str = "svk") -> list[dict]:
    """The 2D cantilever (beam2d, clamped, 62.5 kN tip load) with ``elements`` elements and
    the material ``law`` (svk locks, ecm is the remedy): static tip deflection against
    8.099e-4 m (passes within 1 %)."""
    from runtime.model.model import Model
    from runtime.solve import static as analysis

    p = POISSON
    model = Model(cantilever_scene(
        "beam2d", Material("steel", E=p["E"], nu=nu, rho=7850.0, law=law), elements,
        p["length"], p["height"], p["width"], [PointForce("beam:-1", (0.0, -p["load"]))]))
    result = analysis.solve_static(model, Static())
    tip = -float(result.q[model.node_dofs(elements, "r")][1])
    # svk: against the converged nu = 0.3 reference (the locking and the shear coefficient
    # show); ecm, whose shear correction is Cowper's: against beam theory at the row's nu;
    # the elastic line (no shear deflection): against Euler-Bernoulli's
    reference = (p["reference"] if law == "svk" else euler_bernoulli()
                 if law == "elastic_line" else beam_theory(nu))
    error = tip / reference - 1
    passed = bool(abs(error) <= POISSON_TOLERANCE)
    lam = p["E"] * nu / ((1 + nu) * (1 - 2 * nu))
    shear = p["E"] / (2 * (1 + nu))
    uniform_shear = beam_theory(nu, shear_coefficient=1.0)
    locked = beam_theory(nu, shear_coefficient=1.0, bending_modulus=lam + 2 * shear)
    detail = (f"tip {tip:.5e} m ({error:+.2%}); beam theory at this nu (Cowper's shear "
              f"coefficient) {beam_theory(nu):.4e} m; with shear coefficient 1 "
              f"{uniform_shear:.4e} m")
    if nu > 0:
        detail += (f"; locked (bending modulus lam + 2G = {(lam + 2 * shear) / p['E']:.3f} E, "
                   f"shear coefficient 1) {locked:.4e} m")
    cause = ""
    if not passed and law != "svk":
        theory = ("Euler-Bernoulli beam theory" if law == "elastic_line" else
                  "beam theory at its nu")
        cause = (f"the {law} law against {theory} ({reference:.4e} m): the mesh of "
                 f"{elements} elements adds {error:+.1%} (discretisation: it converges as the "
                 f"mesh is refined)")
    elif not passed:
        if nu > 0:
            cause = (f"Poisson locking: the fully parameterised element's cross-section is "
                     f"linear in y (r_y constant over the height), so the transverse strain "
                     f"cannot follow the Poisson contraction, which varies linearly in y in "
                     f"bending; the bending stress then sees lam + 2G = "
                     f"{(lam + 2 * shear) / p['E']:.3f} E instead of E (Sopanen & Mikkola "
                     f"2003): the locked limit {locked:.4e} m is {locked / p['reference'] - 1:+.1%}"
                     f" from the reference")
        else:
            cause = (f"no locking at nu = 0, but the reference is the nu = 0.3 beam theory "
                     f"(nu = 0 gives {beam_theory(0.0):.4e} m, "
                     f"{beam_theory(0.0) / p['reference'] - 1:+.1%}) and the element's linear "
                     f"cross-section has uniform shear strain (shear coefficient 1, not 5/6): "
                     f"its limit {uniform_shear:.4e} m is "
                     f"{uniform_shear / p['reference'] - 1:+.1%} from the reference")
            if abs(tip / uniform_shear - 1) > 0.5 * POISSON_TOLERANCE:
                cause += (f"; the mesh adds {tip / uniform_shear - 1:+.1%} (discretisation, "
                          f"{elements} elements)")
    return [row_record(group="poisson_locking", case=f"{law}, nu = {nu:g}, {elements} elements",
                 method="gram", measured=error, tolerance=POISSON_TOLERANCE, passed=passed,
                 detail=detail, cause=cause, compare="|x| <=")]


CHRONO_TOLERANCE = 0.02


def chrono_beam_case(law: str, load: str) -> list[dict]:
    """Chrono's 20-element aluminium cantilever (nu = 0.33) under ``load`` (axial: 1 kN
    along x, P L / EA; tip: 10 N across the wide side, P L^3 / 3EI; gravity: distributed,
    q L^4 / 8EI) with the material ``law``: static deflection against the closed form."""
    from runtime.model.model import Model
    from runtime.solve import static as analysis

    c = CHRONO_BEAM
    length, thin, wide, E = c["length"], c["thin"], c["wide"], c["E"]
    # bending across the thin side of the section (local y = height): I = w h^3 / 12
    height, width = (wide, thin) if load == "gravity" else (thin, wide)
    component = 2
    if load == "axial":
        loads = [PointForce("beam:-1", (1000.0, 0.0, 0.0))]
        closed, component = 1000.0 * length / (E * height * width), 0
    elif load == "tip":
        loads = [PointForce("beam:-1", (0.0, 0.0, 10.0))]
        closed = 10.0 * length**3 / (3 * E * height * width**3 / 12)
    else:
        loads = [Gravity((0.0, 0.0, -c["g"]))]
        q = c["rho"] * height * width * c["g"]
        closed = -q * length**4 / (8 * E * height * width**3 / 12)
    model = Model(cantilever_scene(
        "beam3d", Material("al", E=E, nu=c["nu"], rho=c["rho"], law=law), c["elements"],
        length, height, width, loads))
    result = analysis.solve_static(model, Static())
    tip = float((result.q - model.reference)[model.node_dofs(c["elements"], "r")][component])
    error = tip / closed - 1
    passed = bool(abs(error) <= CHRONO_TOLERANCE)
    cause = ""
    if not passed:
        cause = (f"Poisson locking of the {law} law at nu = {c['nu']}: the linear "
                 f"cross-section cannot contract with the bending strain, so bending sees "
                 f"a stiffer modulus; law = \"ecm\" integrates the Poisson part on the axis only"
                 if law == "svk" and load != "axial" else
                 f"{law}, {load}: {error:+.2%} from the closed form")
    return [row_record(group="chrono_beam", case=f"{law}, {load}", method="gram", measured=error,
                 tolerance=CHRONO_TOLERANCE, passed=passed,
                 detail=f"tip {tip:.5e} m, closed form {closed:.5e} m", cause=cause,
                 compare="|x| <=")]
