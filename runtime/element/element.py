"""``runtime.Element``: one ANCF element, its invariants and its generated kernels."""

from __future__ import annotations

import numbers
import reprlib
import time

import numpy as np

from runtime.catalog import BACKENDS, METHODS, family_name
from runtime.element import invariants as inv
from runtime.kernels.boundary import output_array, real_array
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import kernel_family

MAGNITUDE = 1e30  # length, height, width, E and rho lie in [1 / MAGNITUDE, MAGNITUDE]


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lame lambda and shear modulus G (Pa) from Young's modulus (Pa) and Poisson's ratio."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def _real(name: str, value, expected: str) -> float:
    """``value`` (a real number, NumPy scalars included; bools rejected) as a float."""
    if not isinstance(value, bool) and isinstance(value, numbers.Real):
        try:
            return float(value)
        except OverflowError:  # an int beyond the float range
            pass
    raise ValueError(f"{name}: expected {expected}, got {reprlib.repr(value)}")


def _positive(name: str, value) -> float:
    expected = f"a positive finite number between {1 / MAGNITUDE:g} and {MAGNITUDE:g}"
    number = _real(name, value, expected)
    if not 1 / MAGNITUDE <= number <= MAGNITUDE:
        raise ValueError(f"{name}: expected {expected}, got {reprlib.repr(value)}")
    return number


def _choice(name: str, value, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name}: expected one of {choices}, got {reprlib.repr(value)}")
    return str(value)


class Element:
    """An ANCF element of kind ``kind`` with a material law (docs/laws.md).

    length, height, width in m; E in Pa; nu dimensionless in (-1, 0.5); rho in kg/m^3.
    e0: reference coordinates (ndof,), default the straight element along x from the origin;
    any rigid placement of a straight element uses the closed-form invariants, any other
    (curved) reference uses Gauss quadrature of order ``quadrature`` (default: the kind's;
    the axis part of a law uses the first order along the axis).
    method: ``gram`` | ``cij`` | ``quadrature``; backend: ``c`` | ``numpy``.
    law: ``svk`` (St. Venant-Kirchhoff, default) | ``ecm`` (enhanced continuum mechanics, no
    Poisson locking) | ``ecm_sri`` (ecm with selective reduced integration along x: no locking
    of slender 2-node beams in large rotations; general invariants, straight or not) |
    ``svk_sri`` (plates and shells: svk with the plane-stress and shear part at 2 x 2 Gauss
    points of the surface, no membrane or shear locking; general invariants) |
    ``elastic_line`` (2-node beams: a structural Euler-Bernoulli beam of the centre line,
    axial strain, bending r_xx on the nodal frames and torsion along x, shear and section
    strains at the nodes; straight references only; ``section_stiffness`` gives its
    stiffnesses); for
    cables ``svk`` (simple bending) | ``svk_exact_curvature`` (exact curvature bending by
    Gauss quadrature of order ``quadrature[0]`` along the axis);
    shear_correction: the ECM shear-correction factors, one number for every
    transverse shear or a tuple (k1 on 2E13, k2 on 2E12 in 3D; k on 2E12 in 2D), default
    10 (1 + nu) / (12 + 11 nu); damping: Kelvin-Voigt alpha in s (stress = D (eps + alpha
    eps_dot)), used by ``damping_force`` and ``internal_force_and_jacobians``.

    Every invalid argument raises ValueError naming it (wrong types included, so callers catch
    one class): numbers are real (NumPy scalars accepted; bools, strings, NaN and inf
    rejected), length/height/width/E/rho within [1e-30, 1e30], and parameters whose
    invariants overflow float64 are rejected.  Coordinates ``e`` are real arrays (integers
    accepted; complex, bool, object, string, ragged and non-finite values rejected); an empty
    batch (0, ndof) gives empty results.  ``out`` buffers must be writable C-contiguous float64
    arrays of the result's shape (they are filled in place, never copied).

    ``timing`` records the seconds spent loading/compiling kernels and pre-processing.
    """

    def __init__(self, kind: str, length: float, height: float, width: float, E: float,
                 nu: float, rho: float, e0=None, method: str = "gram", backend: str = "c",
                 quadrature=None, law: str = "svk", shear_correction=None,
                 damping: float = 0.0) -> None:
        self._created = time.perf_counter()
        self.kind = element_kind(kind)
        self.geometry = (_positive("length", length), _positive("height", height),
                         _positive("width", width))
        self.E, self.rho = _positive("E", E), _positive("rho", rho)
        self.nu = _real("nu", nu, "Poisson's ratio in (-1, 0.5)")
        if not -1 < self.nu < 0.5:
            raise ValueError(f"nu: expected Poisson's ratio in (-1, 0.5), got {nu!r}")
        self.method = _choice("method", method, METHODS)
        self.backend = _choice("backend", backend, BACKENDS)
        self.quadrature = self._orders(quadrature)
        self.e0 = (self.kind.straight_reference(*self.geometry) if e0 is None
                   else self._coordinates(e0, "e0", batch=False))
        self.straight = inv.is_straight(self.kind, self.e0, self.geometry)
        self.law, self.damping = self._law(law), self._damping(damping)
        #: the law's bending model on a cable (``runtime.catalog.BENDING_MODELS``), else None
        law_info = self.kind.laws[self.law]
        self.bending = law_info.bending
        # a law with reduced integration stores general invariants, straight or not
        self.variant = ("straight" if self.straight and law_info.storage == "straight"
                        else "general")
        if ("straight" if self.straight else "general") not in law_info.variants:
            raise ValueError(f"e0: {self.kind.name} takes straight references only with law "
                             f"{self.law!r} (rigid placements of the straight element): "
                             f"{law_info.curved}")
        self.lam, self.shear = lame(self.E, self.nu)
        self.timing = {"compile_s": 0.0, "load_s": 0.0, "preprocess_s": 0.0}
        self._structural_table: np.ndarray | None = None
        #: kernel families loaded (compiled on first use with backend c), in load order
        self.loaded_families: list[str] = []
        builders = self._family("invariants")
        start = time.perf_counter()
        self.shear_correction = self._shear_correction(shear_correction)
        # svk through its own kernels where the kind has them (the 2-node beams), otherwise
        # (closed forms as data, no general svk map, a structural energy) through the law path
        if self.law == "svk" and not inv.through_laws(self.kind) and (
                not self.kind.energy.structural) and (
                self.straight or "invariants_general" in self.kind.families):
            self.invariants = self._svk_invariants(builders)
        else:
            self.invariants = self._law_invariants(builders)
        self._inputs = self._method_inputs(builders)
        self._check_finite(e0 is not None)
        self.timing["preprocess_s"] += time.perf_counter() - start
        family = family_name(self.method, self.law, self.variant, bending=self.bending,
                             structural=law_info.structural)
        kernels = self._family(family)
        self.family = family
        self._method_kernels = kernels
        fixed = dict(self._inputs, e0=self.e0[None, :])
        self._bound = {name: kernels.bind(name, fixed) for name in kernels.signatures}
        self._damping_bound: dict | None = None
        if self.damping > 0:
            self._damping_kernels()

    # --- material law and damping (docs/laws.md) ------------------------------------------

    def _law(self, law) -> str:
        known = list(self.kind.laws)
        reason = self.kind.law_not_applicable(law) if isinstance(law, str) else None
        if reason is not None:
            raise ValueError(f"law: {reason}; expected one of {tuple(known)} for "
                             f"{self.kind.name}")
        if not isinstance(law, str) or law not in known:
            raise ValueError(f"law: expected one of {tuple(known)}, got {law!r}")
        return law

    @staticmethod
    def _damping(damping) -> float:
        if isinstance(damping, bool) or not isinstance(damping, numbers.Real) \
                or not np.isfinite(damping) or damping < 0:
            raise ValueError(f"damping: expected the Kelvin-Voigt coefficient alpha in s, a "
                             f"finite number >= 0, got {damping!r}")
        return float(damping)

    def _shear_correction(self, value) -> tuple[float, ...]:
        names = self.kind.laws[self.law].corrections
        if not names:
            if value is not None:
                raise ValueError(f"shear_correction: law {self.law!r} takes none (only a law "
                                 "with shear corrections, e.g. 'ecm')")
            return ()
        if value is None:
            return inv.default_corrections(self._family("laws"), self.law, self.E, self.nu)
        values = tuple(value) if np.iterable(value) else (value,) * len(names)
        if len(values) != len(names) or not all(
                not isinstance(k, bool) and isinstance(k, numbers.Real) and np.isfinite(k)
                and k > 0 for k in values):
            raise ValueError(f"shear_correction: expected a positive number or "
                             f"{len(names)} positive numbers ({', '.join(names)}), got {value!r}")
        return tuple(float(k) for k in values)

    def _svk_invariants(self, builders) -> dict:
        mapping = builders if self.straight else self._family("invariants_general")
        if self.straight:
            inv.checked_reference(self.kind, builders, self.geometry, self.e0, self.quadrature)
            integrals = inv.straight_integrals(self.kind, builders, self.geometry)
        else:
            integrals = inv.pattern_integrals(self.kind, self.variant, inv.numeric_integrals(
                self.kind, builders, self.geometry, self.e0, self.quadrature))
        return inv.stored_invariants(mapping, self.variant, integrals,
                                     (self.lam, self.shear, self.rho))

    def _law_invariants(self, builders) -> dict:
        if self.kind.laws[self.law].structural:  # strains of the centre line, by quadrature
            inv.checked_reference(self.kind, builders, self.geometry, self.e0, self.quadrature)
            return inv.structural_invariants(self.kind, builders, self.law, self.variant,
                                             self.geometry, self.quadrature,
                                             self._law_table(builders), self.rho)
        laws = self._family("laws")
        coefficients = self.law_coefficients()
        if self.variant == "straight":
            if not self.kind.energy.structural:  # a cable's J0 has no section to check
                inv.checked_reference(self.kind, builders, self.geometry, self.e0,
                                      self.quadrature)
            if inv.has_closed_tables(self.kind):  # exact tables (closed.json), any law
                return inv.closed_law_invariants(self.kind, self.geometry, coefficients,
                                                 self.rho)
            if inv.straight_by_quadrature(self.kind):  # an exact Gauss rule, cached
                return inv.quadrature_law_invariants(self.kind, builders, self.geometry,
                                                     coefficients, self.rho)
            return inv.straight_law_invariants(laws, self.geometry, coefficients, self.rho,
                                               self._simple_bending_modulus(coefficients))
        if self.kind.energy.structural:  # a curved cable (the planar exact curvature)
            return inv.cable_invariants(self.kind, builders, self.geometry, self.quadrature,
                                        coefficients, self.rho,
                                        self._simple_bending_modulus(coefficients),
                                        self.e0, self.variant)
        rules = self._law_rules(builders)
        return inv.numeric_law_invariants(self.kind, builders, self.variant, self.geometry,
                                          rules, coefficients, self.rho)

    def _simple_bending_modulus(self, coefficients: dict) -> float | None:
        """The modulus of a cable's pre-integrated bending: the E11 coefficient on the axis
        for the simple model, 0 when the bending is by quadrature (None for a continuum)."""
        if self.bending is None:
            return None
        return float(coefficients["axis"][0]) if self.bending == "simple" else 0.0

    def law_coefficients(self) -> dict[str, np.ndarray]:
        """The law's coefficients (Pa) per domain (``volume``, ``axis``): the upper triangle
        of the normal block of its Voigt matrix, then the shear diagonal (docs/laws.md).
        A structural law has none (``section_stiffness``): ValueError."""
        if self.kind.laws[self.law].structural:
            raise ValueError(f"law {self.law!r} has no Voigt coefficients: its strains are "
                             "structural strains of the centre line (section_stiffness "
                             "gives their stiffnesses; docs/laws.md)")
        return inv.law_coefficients(self.kind, self._family("laws"), self.law, self.E,
                                    self.nu, self.shear_correction)

    def section_stiffness(self) -> dict[str, float]:
        """The section stiffness of each strain of a structural law, by strain name (N for
        the stretches and shears, N m^2 for bending and torsion; docs/laws.md); ValueError
        for a law of the Green-Lagrange strain (``law_coefficients``)."""
        info = self.kind.laws[self.law]
        if not info.structural:
            raise ValueError(f"law {self.law!r} has no structural strains (law_coefficients "
                             "gives its Voigt coefficients)")
        values = inv.structural_stiffness(self.kind, self._family("laws"), self.law, self.E,
                                          self.nu, self.shear_correction, self.geometry)
        return {strain["name"]: float(v) for strain, v in zip(info.strains, values,
                                                                strict=True)}

    def _law_rules(self, builders) -> dict:
        return inv.law_rules(self.kind, builders, self.geometry, self.e0, self.quadrature)

    def _law_table(self, builders) -> np.ndarray:
        if self.kind.laws[self.law].structural:
            if self._structural_table is None:
                self._structural_table = inv.structural_table(
                    self.kind, builders, self.law, self.geometry, self.quadrature,
                    np.array(list(self.section_stiffness().values())))
            return self._structural_table
        if self.kind.energy.structural:  # the law that takes curved references has kappa0
            return inv.cable_table(self.kind, builders, self.geometry, self.quadrature[0],
                                   self.law_coefficients(), self.e0,
                                   "general" in self.kind.laws[self.law].variants)
        return inv.law_table(self.kind, self._law_rules(builders), self.law_coefficients())

    def _damping_kernels(self) -> dict:
        """The bound damping kernels (compiled on first use): through the gram invariant for
        gram and cij, by quadrature of the law for quadrature."""
        if self._damping_bound is None:
            start = time.perf_counter()
            alpha = np.array([self.damping])
            family = self.damping_family
            if self.method == "quadrature":
                table = (self._inputs["table"] if self.law != "svk" or self.kind.energy.structural
                         else self._law_table(self._family("invariants")))
                fixed = {"table": table, "alpha": alpha}
            else:
                fixed = {**self._gram_inputs(), "alpha": alpha}
                if self.bending == "exact_curvature":  # the bending loop's table
                    fixed["table"] = self._inputs["table"]
            self.timing["preprocess_s"] += time.perf_counter() - start
            kernels = self._family(family)
            self._damping_family = kernels
            self._damping_fixed = fixed
            bound = dict(fixed, e0=self.e0[None, :])
            self._damping_bound = {name: kernels.bind(name, bound)
                                   for name in ("damping_force", "damped_force_jacobians")}
        return self._damping_bound

    def _run_damped(self, kernel: str, e, e_dot, out: dict) -> tuple[dict, bool]:
        coordinates = np.atleast_2d(self._coordinates(e))
        velocities = np.atleast_2d(self._coordinates(e_dot, "e_dot"))
        if coordinates.shape[0] != velocities.shape[0] and 1 not in (coordinates.shape[0],
                                                                     velocities.shape[0]):
            raise ValueError(f"e_dot: expected as many rows as e ({coordinates.shape[0]}), got "
                             f"{velocities.shape[0]}")
        m = max(coordinates.shape[0], velocities.shape[0])
        coordinates, velocities = (np.ascontiguousarray(np.broadcast_to(x, (m, self.ndof)))
                                   for x in (coordinates, velocities))
        single = np.ndim(e) == 1 and np.ndim(e_dot) == 1
        buffers = {}
        for name, (argument, target) in out.items():
            if target is not None:
                shape = (self.ndof,) if name == "force" else (self.ndof, self.ndof)
                output_array(argument, target, shape if single else (m, *shape))
                buffers[name] = target.reshape(m, -1)
        result = self._damping_kernels()[kernel]({"e": coordinates, "e_dot": velocities},
                                                 buffers)
        return result, single

    def damping_force(self, e, e_dot, out: np.ndarray | None = None) -> np.ndarray:
        """Kelvin-Voigt damping force -alpha int (deps/de)^T D eps_dot dV0 (N), the
        derivative of minus the dissipation potential with respect to e_dot: (ndof,) for one
        (e, e_dot), (m, ndof) for a batch (either may be one row); ``out`` as elastic_force."""
        result, single = self._run_damped("damping_force", e, e_dot, {"force": ("out", out)})
        return result["force"][0] if single else result["force"]

    def internal_force_and_jacobians(self, e, e_dot, out_force: np.ndarray | None = None,
                                     out_jacobian: np.ndarray | None = None,
                                     out_jacobian_dot: np.ndarray | None = None):
        """(force, d force/de, d force/de_dot) of the elastic plus damping force in one kernel
        pass (what an implicit integrator needs): (ndof,), (ndof, ndof), (ndof, ndof) for one
        (e, e_dot), with a leading m for a batch; d force/de_dot, the damping force's alone,
        is symmetric."""
        result, single = self._run_damped("damped_force_jacobians", e, e_dot,
                                          {"force": ("out_force", out_force),
                                           "jacobian": ("out_jacobian", out_jacobian),
                                           "jacobian_dot": ("out_jacobian_dot",
                                                            out_jacobian_dot)})
        shape = (-1, self.ndof, self.ndof)
        force = result["force"]
        de, de_dot = (result["jacobian"].reshape(shape), result["jacobian_dot"].reshape(shape))
        return (force[0], de[0], de_dot[0]) if single else (force, de, de_dot)

    @property
    def damping_family(self) -> str:
        """Name of the kernel family of this element's damping kernels."""
        return family_name(self.method, self.law, self.variant, damped=True,
                           bending=self.bending, structural=self.kind.laws[self.law].structural)

    @property
    def damping_kernel_family(self):
        """The loaded damping kernel family (``runtime.kernels.loader``); compiled on first use."""
        self._damping_kernels()
        return self._damping_family

    @property
    def damping_inputs(self) -> dict:
        """The invariant inputs of the damping kernels, by argument name."""
        self._damping_kernels()
        return dict(self._damping_fixed)

    def damping_group_kernel(self, kernel: str):
        """``kernel`` (damping_force, damped_force_jacobians) for a group
        of elements sharing this element's invariants (as ``group_kernel``): call it with
        ``{"e": (m, ndof), "e0": (m, ndof), "e_dot": (m, ndof)}`` and optional ``out``."""
        self._damping_kernels()
        return self._damping_family.bind(kernel, dict(self._damping_fixed))

    # --- construction helpers ------------------------------------------------------------

    def _family(self, family: str):
        kernels = kernel_family(self.kind.name, family, self.backend)
        # charged once per family (this is called again for a family already loaded), and
        # only if loaded for this element, not before
        if family not in self.loaded_families:
            self.loaded_families.append(family)
            if kernels.loaded_at >= self._created:
                self.timing["compile_s"] += kernels.compile_s
                self.timing["load_s"] += kernels.load_s
        return kernels

    def _orders(self, quadrature) -> tuple[int, ...]:
        if quadrature is None:
            return self.kind.quadrature
        orders = tuple(quadrature) if isinstance(quadrature, (list, tuple, np.ndarray)) else ()
        if len(orders) != self.kind.dim or not all(
                isinstance(o, numbers.Integral) and not isinstance(o, bool) and 1 <= o <= 64
                for o in orders):
            raise ValueError(f"quadrature: expected {self.kind.dim} Gauss orders between 1 "
                             f"and 64 (e.g. {self.kind.quadrature}), got {quadrature!r}")
        return tuple(int(o) for o in orders)

    def _gram_inputs(self) -> dict:
        """The gram tensor and, for the cable's simple bending, the linear term."""
        linear = ("gram_linear",) if self.bending == "simple" else ()
        return {name: self.invariants[name] for name in ("gram", *linear)}

    def _method_inputs(self, builders) -> dict:
        stored = self.invariants
        # the exact curvature's bending loop reads the cable's quadrature table
        table = ({"table": self._law_table(builders)} if self.bending == "exact_curvature"
                 else {})
        if self.method == "gram":
            return {**self._gram_inputs(), **table}
        if self.method == "cij":
            k2, jacobian = inv.cij_operators(self.kind, self.variant, stored["cij"])
            return {"k1": stored["k1"], "u0": stored["u0"], "k2_matrix": k2,
                    "jacobian_matrix": jacobian, **table}
        # a non-default law's quadrature family also holds the damping kernels (alpha)
        alpha = {"alpha": np.array([self.damping])} if self.law != "svk" else {}
        if self.kind.energy.structural:  # the cable's quadrature families: their table
            return {"table": self._law_table(builders), **alpha}
        if self.law != "svk":
            return {"table": self._law_table(builders), **alpha}
        return {"material": np.array([self.lam, self.shear]),
                "table": inv.quadrature_table(self.kind, builders, self.geometry,
                                              self.quadrature)}

    def _check_finite(self, own_reference: bool) -> None:
        """ValueError naming the parameters when the invariants overflow float64."""
        values = [self.lam, self.shear, *self.invariants.values(),
                  *(v for v in self._inputs.values() if isinstance(v, np.ndarray))]
        if not all(np.isfinite(v).all() for v in values):
            length, height, width = self.geometry
            raise ValueError(
                f"length, height, width, E, nu, rho{', e0' if own_reference else ''}: the "
                f"invariants overflow float64 (length={length:g}, height={height:g}, "
                f"width={width:g}, E={self.E:g}, nu={self.nu:g}, rho={self.rho:g}); expected "
                "values of ordinary magnitude (rescale the units)")

    def _coordinates(self, e, name: str = "e", batch: bool = True) -> np.ndarray:
        """``e`` as a finite C-contiguous float64 array, (ndof,) or (m, ndof) (m >= 0)."""
        ndof = self.kind.ndof
        expected = f"({ndof},) or (m, {ndof})" if batch else f"({ndof},)"
        array = real_array(name, e, f"shape {expected} for {self.kind.name}")
        if not (array.ndim == 1 and array.shape[0] == ndof
                or batch and array.ndim == 2 and array.shape[1] == ndof):
            raise ValueError(f"{name}: expected shape {expected} for {self.kind.name}, got "
                             f"{array.shape}")
        array = np.ascontiguousarray(array, dtype=np.float64)
        if not np.isfinite(array).all():
            raise ValueError(f"{name}: contains NaN or infinite values")
        return array

    # --- public API ----------------------------------------------------------------------

    @property
    def ndof(self) -> int:
        """Number of element coordinates."""
        return self.kind.ndof

    def _run(self, kernel: str, e, out: dict | None = None) -> tuple[dict, bool]:
        """Run ``kernel`` on coordinates ``e``; out: {output: (argument name, array | None)}.

        Returns the (m, size) outputs and whether ``e`` was one element."""
        coordinates = self._coordinates(e)
        single = coordinates.ndim == 1
        batch = coordinates[None, :] if single else coordinates
        m, ndof = batch.shape[0], self.ndof
        bound = self._bound[kernel]
        outputs = {}
        for name, size in bound.outputs:
            argument, target = (out or {}).get(name, (None, None))
            if target is None:
                outputs[name] = np.empty((m, size))
            else:
                shape = (ndof,) if name == "force" else (ndof, ndof)
                output_array(argument, target, shape if single else (m, *shape))
                outputs[name] = target.reshape(m, size)
        return bound.unchecked(m, {"e": batch}, outputs), single

    def elastic_force(self, e, out: np.ndarray | None = None) -> np.ndarray:
        """Elastic force -dU/de (N): shape (ndof,) for one e, (m, ndof) for a batch.

        out: optional writable C-contiguous float64 array of the result's shape, filled and
        returned (anything else raises ValueError).
        """
        result, single = self._run("force", e, {"force": ("out", out)})
        return result["force"][0] if single else result["force"]

    def elastic_jacobian(self, e, out: np.ndarray | None = None) -> np.ndarray:
        """d(force)/de (N/m): (ndof, ndof), or (m, ndof, ndof) for a batch (``out`` as above).
        The combined kernel's (``elastic_force_and_jacobian``): a Jacobian-only kernel would
        save a few per cent of a call and double the C a family compiles."""
        result, single = self._run("force_jacobian", e, {"jacobian": ("out", out)})
        jacobian = result["jacobian"].reshape(-1, self.ndof, self.ndof)
        return jacobian[0] if single else jacobian

    def elastic_force_and_jacobian(self, e, out_force: np.ndarray | None = None,
                                   out_jacobian: np.ndarray | None = None):
        """(force, Jacobian) in one kernel pass, which shares their common part (what a
        Newton iteration needs); shapes and ``out_*`` buffers as the two methods above."""
        result, single = self._run("force_jacobian", e, {"force": ("out_force", out_force),
                                                         "jacobian": ("out_jacobian",
                                                                      out_jacobian)})
        force, jacobian = result["force"], result["jacobian"].reshape(-1, self.ndof, self.ndof)
        return (force[0], jacobian[0]) if single else (force, jacobian)

    def strain_energy(self, e):
        """Strain energy U (J): a float for one e, an (m,) array for a batch."""
        result, single = self._run("energy", e)
        energy = result["energy"]
        return float(energy[0, 0]) if single else energy[:, 0].copy()

    def group_kernel(self, kernel: str):
        """``kernel`` (force, energy, force_jacobian) for a group of elements that
        share this element's invariants but each have their own reference: call it with
        ``{"e": (m, ndof), "e0": (m, ndof) or (1, ndof)}`` and optional ``out``, checked as
        ``runtime.kernels.loader.BoundKernel`` documents (C-contiguous float64 input is not copied).

        Valid for rigid placements of this element's reference (invariants are rotation
        and translation invariant), e.g. the elements of a uniformly meshed line or arc.
        """
        return self._method_kernels.bind(kernel, dict(self._inputs))

    @property
    def kernel_family(self):
        """The loaded kernel family of this element's method (``runtime.kernels.loader``)."""
        return self._method_kernels

    @property
    def kernel_inputs(self) -> dict:
        """The invariant inputs of this element's method kernels, by argument name."""
        return dict(self._inputs)

    def mass_matrix(self) -> np.ndarray:
        """Constant consistent mass matrix (kg), (ndof, ndof): int rho S^T S dV0."""
        n = self.kind.n_shape
        shape_mass = np.zeros((n, n))
        rows, cols = np.triu_indices(n)
        shape_mass[rows, cols] = shape_mass[cols, rows] = self.invariants["mass"]
        return np.kron(shape_mass, np.eye(self.kind.dim))

    def __repr__(self) -> str:
        length, height, width = self.geometry
        return (f"Element({self.kind.name!r}, length={length}, height={height}, width={width}, "
                f"E={self.E}, nu={self.nu}, rho={self.rho}, method={self.method!r}, "
                f"backend={self.backend!r}, law={self.law!r}, damping={self.damping}, "
                f"{'straight' if self.straight else 'curved'})")
