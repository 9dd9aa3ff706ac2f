"""The compiled engine: the whole time step of a model in generated C.

For a ``DAESystem``, ``templates/stepper.c.j2`` is rendered with only what the scene needs
(its element groups' kernel calls, its integrator) and compiled once per machine into the
JIT cache (``runtime.kernels.jit``, keyed by the source's hash, so every later run with the same
structure loads it).  The element kernels are not compiled again: the stepper calls the
generated functions of the kernel-family modules the elements already loaded, through
their addresses.  Each call advances a block of steps up to the next output time;
prescribed motions and load factors of the block's step times are computed in Python
beforehand, vectorised, and passed as arrays.  Equations, counters and failure causes are
those of the Python engine (``runtime.solve.python_engine``), which stays the reference.
"""

from __future__ import annotations

import time
from importlib import resources

import jinja2
import numpy as np

from runtime.kernels import jit
from runtime.model.dae import DAESystem
from runtime.model.model import Model
from runtime.solve.linear import single_threaded_blas
from runtime.solve.python_engine import (
    CONTRACTION,
    NON_FINITE,
    SINGULAR,
    Counters,
    Divergence,
    State,
    alpha_parameters,
    initial_state,
    newton_mode,
    newton_not_converged,
)

STEPPER_VERSION = "1"
#: Elements per kernel call: each chunk's Jacobians are assembled while still in cache.
CHUNK = 64
_C_TYPES = {"batch": "const double *, long", "shared": "const double *",
            "csr": "const int *, const int *, const double *", "table": "long, const double *",
            "output": "double *"}


def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FunctionLoader(
            lambda name: resources.files("templates").joinpath(name).read_text()),
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined)


def _kernel_call(arrays: list[dict], slots: dict[str, int], inputs: str = "",
                 outputs: dict[str, str] | None = None) -> tuple[str, str]:
    """(C parameter types, C arguments) of a generated kernel, from its signature.  Invariant
    inputs come from the group's ``{inputs}real``/``ints``/``count`` slots, outputs from the
    group buffers named by ``outputs`` (default: the output's own name)."""
    params, args = ["long"], ["count"]
    batch = {"e": "g->e, n", "e0": "g->e0 + first * n, n", "e_dot": "g->e_dot, n"}
    for a in arrays:
        role, name = a["role"], a["name"]
        if role == "local":
            continue
        params.append(_C_TYPES[role])
        if role == "batch":
            args.append(batch[name])
        elif role == "shared":
            args.append(f"g->{inputs}real[{slots[name]}]")
        elif role == "csr":
            args.append(f"g->{inputs}ints[{2 * slots[name]}], "
                        f"g->{inputs}ints[{2 * slots[name] + 1}], g->{inputs}real[{slots[name]}]")
        elif role == "table":
            args.append(f"g->{inputs}count, g->{inputs}real[{slots[name]}]")
        else:
            args.append(f"g->{(outputs or {}).get(name, name)}")
    return ", ".join(params), ", ".join(args)


def _input_slots(signatures: dict, kernels: tuple[str, ...]) -> dict[str, int]:
    """Slot of every invariant input of ``kernels`` of one family."""
    names: list[str] = []
    for kernel in kernels:
        for a in signatures[kernel]["arrays"]:
            if a["role"] in ("shared", "csr", "table") and a["name"] not in names:
                names.append(a["name"])
    return {name: i for i, name in enumerate(names)}


ELASTIC = ("force", "force_jacobian")
DAMPING = ("damping_force", "damped_force_jacobians")


def render(dae: DAESystem, integrator: str) -> tuple[str, str]:
    """(C source, cffi declarations) of the stepper of ``dae`` with ``integrator``."""
    env = _environment()
    groups, slots_needed = [], 1
    for group in dae.groups:
        signatures = group.element.kind.families[group.family]
        slots = _input_slots(signatures, ELASTIC)
        slots_needed = max(slots_needed, 2 * len(slots))
        force_params, force_args = _kernel_call(signatures["force"]["arrays"], slots)
        fj_params, fj_args = _kernel_call(signatures["force_jacobian"]["arrays"], slots)
        entry = {"ndof": group.dofs.shape[1], "force_params": force_params,
                 "force_args": force_args, "force_jacobian_params": fj_params,
                 "force_jacobian_args": fj_args, "damped": group.element.damping > 0}
        if entry["damped"]:
            damping = group.element.kind.families[group.element.damping_family]
            slots = _input_slots(damping, DAMPING)
            slots_needed = max(slots_needed, 2 * len(slots))
            entry["damping_params"], entry["damping_args"] = _kernel_call(
                damping["damping_force"]["arrays"], slots, "damping_",
                {"force": "force_damping"})
            entry["damped_params"], entry["damped_args"] = _kernel_call(
                damping["damped_force_jacobians"]["arrays"], slots, "damping_")
        entry["index"] = len(groups)
        groups.append(entry)
    kinds = ", ".join(sorted({f"{g.kind}/{g.family}" for g in dae.groups}))
    banner = (f"Generated by runtime.solve.compiled_engine (version {STEPPER_VERSION}) for "
              f"{kinds}, {integrator}. Do not edit.")
    header = env.get_template("stepper_header.h.j2").render(
        banner=banner, groups=groups, slots=slots_needed)
    source = env.get_template("stepper.c.j2").render(
        banner=banner, header=header, groups=groups, integrator=integrator, chunk=CHUNK,
        bandwidth=dae.bandwidth, damped=any(g["damped"] for g in groups))
    return source, header


class CompiledEngine:
    """Runs a dynamic analysis with the generated stepper; the interface of
    ``runtime.solve.python_engine.Integrator`` (``run``, ``counters``)."""

    engine = "compiled"

    def __init__(self, model: Model, settings, q_full: np.ndarray) -> None:
        if model.backend != "c":
            raise ValueError("engine: the compiled engine needs backend = \"c\"; use "
                             "engine = \"python\" with the numpy backend")
        self.settings = settings
        self.newton = newton_mode(settings)
        self.integrator = settings.integrator
        self.dae = DAESystem(model, q_full)
        self.counters = Counters()
        self.timing = {"steps_s": 0.0, "kernel_s": 0.0, "factorisation_s": 0.0}
        source, cdef = render(self.dae, self.integrator)
        start = time.perf_counter()
        compiled = jit.compile_module("stepper", source, cdef,
                                      label=f"stepper/{self.integrator}")
        self.compile_s = compiled.seconds if compiled.compiled or compiled.waited else 0.0
        self.load_s = time.perf_counter() - start - self.compile_s
        self.modules = [f"stepper/{self.integrator}"]
        self._ffi, self._lib = compiled.module.ffi, compiled.module.lib
        self._keep: list = []

    # --- binding arrays ----------------------------------------------------------------

    def _buffer(self, array, ctype: str = "double"):
        dtype = np.float64 if ctype == "double" else np.int32
        array = np.ascontiguousarray(array, dtype=dtype)
        if array.size == 0:
            array = np.zeros(1, dtype)
        self._keep.append(array)
        return self._ffi.from_buffer(f"{ctype}[]", array)

    def _csr(self, matrix, prefix: str, target) -> None:
        matrix = matrix.tocsr()
        setattr(target, f"{prefix}_indptr", self._buffer(matrix.indptr, "int"))
        setattr(target, f"{prefix}_indices", self._buffer(matrix.indices, "int"))
        setattr(target, f"{prefix}_data", self._buffer(matrix.data))

    def _work(self, size: int, ctype: str = "double"):
        return self._buffer(np.zeros(max(size, 1), np.float64 if ctype == "double"
                                     else np.int32), ctype)

    def _model(self, step: float):
        dae, ffi = self.dae, self._ffi
        m = ffi.new("ancf_model *")
        nf, nj, bw = dae.free.size, dae.joints, dae.bandwidth
        m.size, m.nf, m.np, m.nj, m.bw = dae.size, nf, dae.prescribed.size, nj, bw
        m.nloads = len(dae.load_laws)
        position = np.full(dae.size, -1)
        position[dae.free] = np.arange(nf)
        m.free_index = self._buffer(dae.free, "int")
        m.prescribed_index = self._buffer(dae.prescribed, "int")
        m.position = self._buffer(position, "int")
        m.mass_band = self._buffer(dae.mass_band.T)       # column j: rows j - bw .. j
        self._csr(dae.mass_fp, "mfp", m)
        self._csr(dae.joints_free, "af", m)
        self._csr(dae.joints_prescribed, "ap", m)
        m.joint_fixed = self._buffer(dae.joint_fixed_part)
        m.projector = self._buffer(dae.projector)
        m.load_vectors = self._buffer(dae.load_vectors)
        m.h = step
        m.tolerance = self.settings.tolerance * dae.scale
        m.contraction = CONTRACTION
        m.alpha_m, m.alpha_f, m.gamma, m.beta = alpha_parameters(self.settings.rho_inf)
        m.max_iterations = self.settings.max_iterations
        m.modified = int(self.newton == "modified")
        m.factor_kind = 0
        for index, group in enumerate(dae.groups):
            self._group(m.groups[index], group)
        ld = bw + 1
        m.q_full = self._buffer(dae.fixed_values.copy())
        m.f_full = self._work(dae.size)
        m.v_full = self._work(dae.size)
        for name in ("force", "residual", "x", "a_old", "base", "base_v", "v_iter",
                     "abar_new"):
            setattr(m, name, self._work(nf))
        m.band = self._work(nf * ld)
        m.lu = self._work(nf * (3 * bw + 1))
        m.lu_pivots = self._work(nf, "int")
        m.coupling = self._work(nf * nj)
        m.schur = self._work(nj * nj)
        m.schur_pivots = self._work(nj, "int")
        m.work = self._work(ld)
        m.y = self._work(nj)
        return m

    def _group(self, target, group) -> None:
        element = group.element
        signatures = element.kind.families[group.family]
        inputs = element.kernel_inputs
        elements, ndof = group.dofs.shape
        target.elements = elements
        target.dofs = self._buffer(group.dofs, "int")
        target.e0 = self._buffer(group.e0)
        self._inputs(target, "", _input_slots(signatures, ELASTIC), inputs)
        family = element.kernel_family
        for kernel in ELASTIC:
            setattr(target, f"{kernel}_kernel", self._ffi.cast("void *", family.address(kernel)))
        chunk = min(elements, CHUNK)
        target.e = self._work(chunk * ndof)
        target.force = self._work(chunk * ndof)
        target.jacobian = self._work(chunk * ndof * ndof)
        if element.damping > 0:
            damping = element.kind.families[element.damping_family]
            self._inputs(target, "damping_", _input_slots(damping, DAMPING),
                         element.damping_inputs)
            family = element.damping_kernel_family
            for kernel in DAMPING:
                setattr(target, f"{kernel}_kernel",
                        self._ffi.cast("void *", family.address(kernel)))
            target.e_dot = self._work(chunk * ndof)
            target.force_damping = self._work(chunk * ndof)
            target.jacobian_dot = self._work(chunk * ndof * ndof)

    def _inputs(self, target, prefix: str, slots: dict[str, int], inputs: dict) -> None:
        """Bind invariant inputs into the group's ``{prefix}real/ints/count`` slots."""
        real, ints = getattr(target, f"{prefix}real"), getattr(target, f"{prefix}ints")
        for name, slot in slots.items():
            value = inputs[name]
            if hasattr(value, "indptr"):
                ints[2 * slot] = self._buffer(value.indptr, "int")
                ints[2 * slot + 1] = self._buffer(value.indices, "int")
                real[slot] = self._buffer(value.data)
            else:
                value = np.asarray(value, float)
                if value.ndim == 2:      # a quadrature table: (points, width)
                    setattr(target, f"{prefix}count", value.shape[0])
                real[slot] = self._buffer(value)

    def _state(self, state):
        s = self._ffi.new("ancf_state *")
        self._state_arrays = [np.ascontiguousarray(x, dtype=float).copy() for x in
                              (state.q, state.v, state.a, state.multipliers,
                               state.extra.get("abar", state.a))]
        for name, array in zip(("q", "v", "a", "lam", "abar"), self._state_arrays,
                               strict=True):
            setattr(s, name, self._buffer(array))
        s.dissipated, s.power = state.extra["dissipated"], state.extra["power"]
        return s

    # --- the loop ----------------------------------------------------------------------

    def run(self, t_end: float, step: float, observe, progress=None):
        """Integrate from rest at t = 0 to ``t_end``; ``observe(t, q_full, v_full)`` at t = 0
        and every ``output_every`` seconds, as the Python engine.  Raises Divergence."""
        with single_threaded_blas():
            return self._run(t_end, step, observe, progress)

    def _run(self, t_end: float, step: float, observe, progress) -> State:
        dae = self.dae
        state = initial_state(dae)
        m = self._model(step)
        s = self._state(state)
        q, v = self._state_arrays[0], self._state_arrays[1]
        every = self.settings.output_every or step
        steps = int(round(t_end / step))
        stride = max(1, int(round(every / step)))

        def emit(t: float) -> None:
            qp, vp, _ = (x[0] for x in dae.prescribed_motion([t]))
            dae.model.dissipated_energy = s.dissipated
            observe(t, dae.full_coordinates(q, qp), dae.full_velocities(v, vp))

        emit(0.0)
        first = 1
        try:
            while first <= steps:
                last = min(steps, ((first - 1) // stride + 1) * stride)  # next output
                times = np.arange(first, last + 1) * step
                block = [*dae.prescribed_motion(times), dae.load_factors(times)]
                status = self._lib.ancf_advance(m, s, first, last - first + 1,
                                                *map(self._block_array, block))
                self._sync(s)
                if status:
                    raise Divergence(s.failed_at, self._cause(status, s))
                emit(last * step)
                if progress is not None:
                    progress.update(last * step)
                first = last + 1
        finally:
            self._sync(s)
        arrays = self._state_arrays
        extra = {"dissipated": s.dissipated, "power": s.power}
        if self.integrator == "generalized_alpha":
            extra["abar"] = arrays[4]
        return State(steps * step, arrays[0], arrays[1], arrays[2], arrays[3], extra)

    def _block_array(self, array: np.ndarray):
        """A block's (steps, columns) array as a C pointer (NULL when it has no columns);
        the caller keeps ``array`` alive for the call."""
        if not array.size:
            return self._ffi.NULL
        return self._ffi.from_buffer("double[]", np.ascontiguousarray(array))

    def _sync(self, s) -> None:
        c = self.counters
        c.steps, c.newton_iterations = s.steps, s.newton_iterations
        c.force_evaluations, c.jacobian_evaluations = s.force_evaluations, s.jacobian_evaluations
        c.factorisations = s.factorisations
        self.timing = {"steps_s": s.advance_seconds, "kernel_s": s.kernel_seconds,
                       "factorisation_s": s.factor_seconds}

    def _cause(self, status: int, s) -> str:
        if status == 1:
            return NON_FINITE
        if status == 2:
            return newton_not_converged(self.settings.max_iterations, s.last_correction)
        return SINGULAR
