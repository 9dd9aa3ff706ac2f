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

import os
import time

import numpy as np
import scipy.sparse

from runtime.catalog import NEWTON_MODES
from runtime.kernels import abi, jit
from runtime.model.dae import DAESystem
from runtime.model.items.force_elements import FORCE_LAWS
from runtime.model.model import Model
from runtime.model.settings import Dynamic
from runtime.model.sliding_rows import (
    DEGREE,
    PARAMETER_ITERATIONS,
    PARAMETER_TOLERANCE,
    SlideError,
    SlidingBlock,
    left_the_body,
    no_closest_point,
)
from runtime.model.time_laws import LoadFunctionError
from runtime.solve import cholmod, lapack, linear, newton_cost
from runtime.solve.linear import single_threaded_blas
from runtime.solve.python_engine import (
    CONTRACTION,
    MAX_FULL_STEPS,
    NON_FINITE,
    PROJECTION_FAILED,
    SINGULAR,
    TALLY_WINDOW,
    Counters,
    Divergence,
    State,
    alpha_parameters,
    dae_system,
    initial_state,
    linear_solver,
    mass_solver,
    newton_mode,
    newton_not_converged,
    one_by_one,
    uses_kkt,
)
from runtime.solve.static import Convergence, ConvergenceError, load_factors
from templates import environment

STEPPER_VERSION = "7"
#: Elements per kernel call: each chunk's Jacobians are assembled while still in cache.
CHUNK = 64
#: on several threads, chunks computed (by the next free thread) in a block while the
#: block before is added in order, per thread: a thread descheduled by other work on the
#: machine holds up one chunk of a block, not every chunk after its own (docs/design.md,
#: "Threads")
BLOCK_CHUNKS_PER_THREAD = 4
#: the automatic thread count: the cores (at most MAX_THREADS) when one evaluation of the
#: element kernels counts at least THREAD_OPERATIONS operations and at least
#: THREAD_OPERATIONS_PER_ENTRY per entry of their Jacobians (the entries are added in chunk
#: order, on one thread at a time), else one (docs/design.md, "Threads")
THREAD_OPERATIONS, THREAD_OPERATIONS_PER_ENTRY, MAX_THREADS = 20_000_000, 50.0, 4


def kernel_threads(dae: DAESystem, requested: int | None) -> int:
    """The threads of the compiled step's element kernels: ``requested`` (the scene's
    ``[solver] threads``), or the automatic count.  A chunk of elements' kernels runs on
    each thread and their sums stay in chunk order: bit for bit those of one thread."""
    if requested is not None:
        return requested
    _, operations, entries = newton_cost.kernel_work(dae)
    if operations < THREAD_OPERATIONS or operations < THREAD_OPERATIONS_PER_ENTRY * entries:
        return 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
        os.cpu_count() or 1)
    return max(1, min(cores, MAX_THREADS))


def passive_waiting() -> None:
    """OpenMP threads that wait sleep (``OMP_WAIT_POLICY=PASSIVE``, unless the user set a
    policy) instead of spinning: on a shared machine a spinning thread takes the core that
    the factorisation or the other kernel thread needs (measured: plate 32 x 32 on two
    threads at a load of 2, 164-167 ms a step spinning, 131-137 sleeping, 127-130 on one
    thread).  Read by libgomp when it loads, with the first stepper on threads."""
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


#: a call of the compiled step covers as many output times as the previous calls' time per
#: output says fit in this (s), up to MAX_BLOCK_OUTPUTS of them (the interrupt and progress
#: latency stays short, the calls few)
BLOCK_SECONDS = 0.05
MAX_BLOCK_OUTPUTS = 1024


def _kernel_call(signature: dict, slots: dict[str, int], inputs: str = "",
                 outputs: dict[str, str] | None = None) -> tuple[str, str]:
    """(C parameter types, C arguments) of a generated kernel, from its element.json entry
    (``runtime.kernels.abi``).  Invariant inputs come from the group's
    ``{inputs}real``/``ints``/``count`` slots, outputs from the group buffers named by
    ``outputs`` (default: the output's own name)."""
    batch = {"e": ("w_e", "n"), "e0": ("g->e0 + first * n", "n"), "e_dot": ("w_e_dot", "n")}
    args = []
    for p in abi.parameters(signature):
        if p.part == "count":
            args.append("count")
        elif p.role == "batch":
            values, stride = batch[p.array]
            args.append(stride if p.part == "stride" else values)
        elif p.role == "output":     # the calling thread's chunk buffers (w_force, ...)
            args.append(f"w_{(outputs or {}).get(p.array, p.array)}")
        elif p.part == "indptr":
            args.append(f"g->{inputs}ints[{2 * slots[p.array]}]")
        elif p.part == "indices":
            args.append(f"g->{inputs}ints[{2 * slots[p.array] + 1}]")
        elif p.part == "points":
            args.append(f"g->{inputs}count")
        else:
            args.append(f"g->{inputs}real[{slots[p.array]}]")
    return abi.c_types(signature), ", ".join(args)


def _input_slots(signatures: dict, kernels: tuple[str, ...]) -> dict[str, int]:
    """Slot of every invariant input of ``kernels`` of one family."""
    names = dict.fromkeys(name for kernel in kernels
                          for name in abi.invariant_inputs(signatures[kernel]))
    return {name: i for i, name in enumerate(names)}


ELASTIC = ("force", "force_jacobian")
DAMPING = ("damping_force", "damped_force_jacobians")


def sliding_blocks(dae: DAESystem) -> list[SlidingBlock]:
    """The sliding joints' blocks of ``dae``'s constraint rows (a callback of the step)."""
    return [block for block in dae.holonomic.blocks if isinstance(block, SlidingBlock)]


def render(dae: DAESystem, integrator: str, solver: str = "banded",
           kkt: bool = False) -> tuple[str, str]:
    """(C source, cffi declarations) of the stepper of ``dae`` with ``integrator`` and the
    linear solver ``solver`` (``runtime.catalog.LINEAR_SOLVERS``); ``kkt``: the joints
    through the KKT system (``runtime.solve.linear.KKTSystem``, with ``sparse``) instead of
    the Schur complement."""
    env = environment()
    groups, slots_needed = [], 1
    for group in dae.groups:
        signatures = group.element.kind.families[group.family]
        slots = _input_slots(signatures, ELASTIC)
        slots_needed = max(slots_needed, 2 * len(slots))
        force_params, force_args = _kernel_call(signatures["force"], slots)
        fj_params, fj_args = _kernel_call(signatures["force_jacobian"], slots)
        entry = {"ndof": group.dofs.shape[1], "force_params": force_params,
                 "force_args": force_args, "force_jacobian_params": fj_params,
                 "force_jacobian_args": fj_args, "damped": group.element.damping > 0}
        if entry["damped"]:
            damping = group.element.kind.families[group.element.damping_family]
            slots = _input_slots(damping, DAMPING)
            slots_needed = max(slots_needed, 2 * len(slots))
            entry["damping_params"], entry["damping_args"] = _kernel_call(
                damping["damping_force"], slots, "damping_",
                {"force": "force_damping"})
            entry["damped_params"], entry["damped_args"] = _kernel_call(
                damping["damped_force_jacobians"], slots, "damping_")
        entry["index"] = len(groups)
        groups.append(entry)
    kinds = ", ".join(sorted({f"{g.kind}/{g.family}" for g in dae.groups}))
    banner = (f"Generated by runtime.solve.compiled_engine (version {STEPPER_VERSION}) for "
              f"{kinds}, {integrator}, {solver} linear solver"
              f"{', KKT joints' if kkt else ''}. Do not edit.")
    state = {"follower": bool(dae.state_loads),
             "follower_callback": bool(dae.state_loads.called),
             "force_elements": bool(dae.state_loads.compiled),
             "sliding": bool(sliding_blocks(dae))}
    header = env.get_template("stepper_header.h.j2").render(
        banner=banner, groups=groups, slots=slots_needed, holonomic=dae.nonlinear, **state)
    source = env.get_template("stepper.c.j2").render(
        banner=banner, header=header, groups=groups, integrator=integrator, chunk=CHUNK,
        bandwidth=dae.bandwidth, damped=any(g["damped"] for g in groups), **state,
        sparse=solver == "sparse", kkt=kkt, cholmod_structs=cholmod.STRUCTS.strip(),
        lapack_band=dae.bandwidth >= lapack.LAPACK_BANDWIDTH, holonomic=dae.nonlinear,
        dim=dae.dim, sliding_degree=DEGREE, sliding_iterations=PARAMETER_ITERATIONS,
        sliding_tolerance=repr(PARAMETER_TOLERANCE))
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
        self.dae = dae_system(model, q_full)
        self.counters = Counters()
        self.timing = {"steps_s": 0.0, "kernel_s": 0.0, "factorisation_s": 0.0,
                       "solve_s": 0.0, "constraint_s": 0.0}
        self.linear = linear_solver(self.dae)
        #: the name of the linear solver (``runtime.catalog.LINEAR_SOLVERS``)
        self.linear_solver = self.linear.name
        #: auto Newton: what a new Jacobian costs in iterations without one
        self.jacobian_weight = newton_cost.jacobian_weight(self.dae, self.linear)
        #: the joints through the KKT system (many rows, sparse solver), else their Schur
        #: complement: the Python engine's choice
        self.kkt = uses_kkt(self.dae, self.linear)
        #: threads of the element kernels (``kernel_threads``)
        self.threads = kernel_threads(self.dae, model.scene.solver.threads)
        source, cdef = render(self.dae, self.integrator, self.linear_solver, self.kkt)
        if self.threads > 1:
            passive_waiting()
        start = time.perf_counter()
        compiled = jit.compile_module("stepper", source, cdef,
                                      label=f"stepper/{self.integrator}",
                                      openmp=self.threads > 1)
        self.compile_s = compiled.seconds if compiled.compiled or compiled.waited else 0.0
        self.load_s = time.perf_counter() - start - self.compile_s
        self.modules = [f"stepper/{self.integrator}"]
        self._ffi, self._lib = compiled.module.ffi, compiled.module.lib
        self._keep: list = []
        #: the constant mass matrix with the joints, factorised once (``mass_solver``)
        self.mass = mass_solver(self.dae)
        #: the step's model for the settings' time step, bound before the run (its arrays
        #: are constant; a second run or another step binds a new one: the step keeps its
        #: factorisation in it)
        self._prepared = self._model(settings.step) if settings.step else None

    # --- binding arrays ----------------------------------------------------------------

    def _buffer(self, array, ctype: str = "double"):
        dtype = {"double": np.float64, "int": np.int32, "long": np.int64}[ctype]
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
        nf, nj, bw = dae.free.size, dae.constraint_rows, dae.bandwidth
        m.size, m.nf, m.np, m.nj, m.bw = dae.size, nf, dae.prescribed.size, nj, bw
        m.nlin = dae.joints
        m.nloads = len(dae.load_laws)
        m.free_index = self._buffer(dae.free, "int")
        m.prescribed_index = self._buffer(dae.prescribed, "int")
        m.position = self._buffer(dae.model.free_position, "int")
        sparse = self.linear_solver == "sparse"
        # column j: rows j - bw .. j (the sparse solver multiplies by M in the pattern)
        m.mass_band = self._buffer(np.zeros(1) if sparse else dae.mass_band.T)
        self._csr(dae.mass_fp, "mfp", m)
        rows = dae.joints_free
        if dae.nonlinear:    # the quadratic rows' structure; the callback fills their values
            h, joints = dae.holonomic, dae.joints_free
            self._af_data = np.concatenate([joints.data, np.zeros(h.free_indices.size)])
            rows = scipy.sparse.csr_matrix(
                (self._af_data, np.concatenate([joints.indices, h.free_indices]),
                 np.concatenate([joints.indptr, joints.nnz + h.free_indptr[1:]])),
                shape=(nj, nf))
        self._csr(rows, "af", m)
        self._csr(dae.joints_prescribed, "ap", m)
        m.joint_fixed = self._buffer(dae.joint_fixed_part)
        m.projector = self._buffer(dae.projector)
        m.load_vectors = self._buffer(dae.load_vectors)
        m.h = step
        m.tolerance = self.settings.tolerance * dae.scale
        m.relative_tolerance, m.length_scale = self.settings.tolerance, dae.scale
        m.contraction = CONTRACTION
        m.alpha_m, m.alpha_f, m.gamma, m.beta = alpha_parameters(self.settings.rho_inf)
        m.max_iterations = self.settings.max_iterations
        m.threads = self.threads
        m.block_chunks = self._block_chunks()
        m.newton = NEWTON_MODES.index(self.newton)     # the template's NEWTON_* order
        m.max_full_steps = MAX_FULL_STEPS
        m.jacobian_weight, m.tally_window = self.jacobian_weight, TALLY_WINDOW
        m.factor_kind = 0
        for index, group in enumerate(dae.groups):
            self._group(m.groups[index], group)
        if dae.state_loads:
            self._follower(m)
        ld = bw + 1
        self._q_full, self._v_full = dae.fixed_values.copy(), np.zeros(dae.size)
        m.q_full = self._buffer(self._q_full)
        m.f_full = self._work(dae.size)
        m.v_full = self._buffer(self._v_full)
        if dae.nonlinear:
            self._holonomic(m)
        for name in ("force", "residual", "x", "a_old", "base", "base_v", "v_iter",
                     "abar_new", "saved_q", "saved_v", "saved_a", "saved_abar"):
            setattr(m, name, self._work(nf))
        if sparse:
            self._sparse(m)
            ld = bw = 0                  # no band
        schur_rows = nj                  # the Schur complement's (none with the KKT system)
        if self.kkt:
            self._kkt(m, rows)
            schur_rows = 0
        if dae.nonlinear and self.integrator == "trapezoidal":
            self._projection(m, rows, ld)
        m.band = self._work(nf * ld)
        m.work = self._work(ld)
        m.lu = self._work(nf * (3 * bw + 1))
        m.lu_pivots = self._work(nf, "int")
        m.coupling = self._work(nf * schur_rows)
        m.solve_work = self._work(nf * schur_rows)
        m.schur = self._work(schur_rows * schur_rows)
        m.schur_pivots = self._work(schur_rows, "int")
        for name, address in lapack.functions().items():
            setattr(m, name, self._ffi.cast("void *", address))
        m.y = self._work(nj)
        if sliding_blocks(dae):
            self._sliding(m, ld, bw)
        m.saved_lam = self._work(nj)
        return m

    def _follower(self, m) -> None:
        """Bind the state loads' Jacobian entries at the pattern slots the loads use (free
        positions of rows and columns), the force elements as data (``_force_elements``)
        and the other loads: a Python callback (``StateLoads.evaluate``) called by the step
        once per force evaluation."""
        dae, ffi = self.dae, self._ffi
        pattern = dae.model.pattern
        slots = np.unique(np.concatenate([s[s >= 0].ravel() for _, _, s in
                                          dae.state_loads.loads]))
        rows = np.repeat(np.arange(pattern.shape[0]), np.diff(pattern.indptr))[slots]
        m.nfollower = slots.size
        m.follower_rows = self._buffer(rows, "int")
        m.follower_cols = self._buffer(pattern.indices[slots], "int")
        m.follower_data = self._work(slots.size)
        m.follower_data_dot = self._work(slots.size)
        if dae.state_loads.compiled:
            self._force_elements(m, slots)
        called = dae.state_loads.called
        if not called:
            return
        size, nloads = dae.size, len(dae.load_laws)

        def evaluate(q_full, v_full, t, loads, jacobian, f_full, data, data_dot) -> None:
            forces = np.frombuffer(ffi.buffer(f_full, 8 * size))
            try:
                q = np.frombuffer(ffi.buffer(q_full, 8 * size))
                v = np.frombuffer(ffi.buffer(v_full, 8 * size))
                factors = np.frombuffer(ffi.buffer(loads, 8 * nloads))
                force, values, dots = dae.state_loads.evaluate(q, factors, bool(jacobian), v, t,
                                                               called)
                forces += force
                if jacobian:
                    np.frombuffer(ffi.buffer(data, 8 * slots.size))[:] += values[slots]
                    if dots is not None:
                        np.frombuffer(ffi.buffer(data_dot, 8 * slots.size))[:] += dots[slots]
            except Exception as error:   # reported after the call (a non-finite force)
                self._callback_error = error
                forces[:] = np.nan

        self._callback_error: Exception | None = None
        self._callback = ffi.callback("void(*)(const double *, const double *, double, "
                                      "const double *, int, double *, double *, double *)",
                                      evaluate)
        m.follower = self._callback

    def _force_elements(self, m, slots: np.ndarray) -> None:
        """Bind the force elements as data of the step's ``force_elements`` (the header
        says the layout): per element its law, load, coordinates, rows (constant, linear
        part, Hessian entries), parameters and the follower_data entry (place in
        ``slots``, the pattern slots of follower_data) of each pair of its coordinates."""
        laws, loads, dofs, constants, linear, parameters, slot_list = [], [], [], [], [], [], []
        hi, hj, hv = [], [], []
        dofptr, rowptr, gptr, hptr, parptr, slotptr = [0], [0], [], [0], [0], [0]
        for index, evaluate, pattern_slots in self.dae.state_loads.compiled:
            element = evaluate.compiled()
            forms, k = element.forms, element.forms.dofs.size
            assert np.array_equal(forms.dofs, evaluate.dofs[0])
            laws.append(FORCE_LAWS.index(element.law))
            loads.append(index)
            dofs.extend(forms.dofs)
            dofptr.append(len(dofs))
            for r in range(forms.rows):
                gptr.append(len(linear))
                linear.extend(forms.linear[r])
                constants.append(forms.constant[r])
                i, j = np.nonzero(forms.hessians[r])
                hi.extend(i)
                hj.extend(j)
                hv.extend(forms.hessians[r][i, j])
                hptr.append(len(hv))
            rowptr.append(len(constants))
            parameters.extend(element.parameters)
            parptr.append(len(parameters))
            pairs = pattern_slots[0].ravel()
            slot_list.extend(np.where(pairs >= 0, np.searchsorted(slots, pairs), -1))
            slotptr.append(len(slot_list))
        m.nforce = len(laws)
        for name, values in (("law", laws), ("load", loads), ("dofptr", dofptr),
                             ("dofs", dofs), ("rowptr", rowptr), ("gptr", gptr),
                             ("hptr", hptr), ("hi", hi), ("hj", hj), ("parptr", parptr),
                             ("slotptr", slotptr), ("slot", slot_list)):
            setattr(m, f"fe_{name}", self._buffer(np.array(values, np.int64), "long"))
        for name, values in (("c", constants), ("g", linear), ("hv", hv),
                             ("par", parameters)):
            setattr(m, f"fe_{name}", self._buffer(np.array(values, float)))
        k = int(np.diff(dofptr).max())
        rows = int(np.diff(rowptr).max())
        m.fe_work = self._work(3 * k + 3 * rows + 3 * rows * k + 2 * rows * rows + 2 * k * k)
        m.fe_turned, m.fe_angle = self._work(m.nforce), self._work(m.nforce)

    def _holonomic(self, m) -> None:
        """Bind the quadratic constraint rows as data for the step's ``quadratic_rows``
        (per term its row, its factor, coordinates, linear parts, Hessian entries, constant;
        the header says the layout)."""
        dae, model = self.dae, self.dae.model
        h, offset = dae.holonomic, dae.joints_free.nnz
        free = np.zeros(dae.size, bool)
        free[dae.free] = True
        a_list, g_list, af_list, b_list, h_list, slot_list = [], [], [], [], [], []
        row_list, factor_list, c_list = [], [], []
        aptr, hptr, first = [0], [0], 0
        for block, slots in zip(h.blocks, model.holonomic_slots, strict=True):
            rank = np.cumsum(free[block.dofs]) - 1       # place among the free columns
            for part, factor in block.terms:       # a term's dofs lead the block's
                for r in range(part.rows):
                    for j, a in enumerate(part.dofs):
                        a_list.append(a)
                        g_list.append(part.linear[r, j])
                        af_list.append(offset + h.free_indptr[first + r] + rank[j]
                                       if free[a] else -1)
                        nonzero = np.flatnonzero(part.hessians[r, j])
                        b_list.extend(part.dofs[nonzero])
                        h_list.extend(part.hessians[r, j, nonzero])
                        slot_list.extend(slots[j, nonzero])
                        hptr.append(len(b_list))
                    aptr.append(len(a_list))
                    row_list.append(first + r)
                    factor_list.append(factor)
                    c_list.append(part.constant[r])
            first += block.rows
        m.nrows_h, m.nterms_h = h.rows, len(row_list)
        for name, values in (("h_aptr", aptr), ("h_a", a_list), ("h_af", af_list),
                             ("h_hptr", hptr), ("h_b", b_list), ("h_slot", slot_list),
                             ("h_row", row_list), ("h_factor", factor_list)):
            setattr(m, name, self._buffer(np.array(values, np.int64), "long"))
        for name, values in (("h_g", g_list), ("h_h", h_list), ("h_c", c_list)):
            setattr(m, name, self._buffer(np.array(values, float)))
        m.holonomic_value = self._work(h.rows)
        m.a_full = self._work(dae.size)
        m.af_kept = self._work(self._af_data.size)

    def _sliding(self, m, ld: int, bw: int) -> None:
        """Bind the sliding joints' rows (``runtime.model.sliding_rows``: not quadratic, their
        parameter eliminated by a closest-point search) as data for the step's
        ``sliding_rows`` (the header says the layout): per joint its point and its map, its
        line's elements and the polynomial coefficients of their shape functions on the
        axis, its rows' directions, and per element the constraint CSR entries and the
        iteration-matrix slots of its local coordinates."""
        dae = self.dae
        model, h = dae.model, dae.holonomic
        offset = dae.joints_free.nnz
        sparse = self.linear_solver == "sparse"
        names = ("row", "pptr", "pdof", "pmapptr", "elements", "ndof", "edofptr", "edof",
                 "polyptr", "nptr", "order", "afptr", "af", "targetptr", "target", "afstart",
                 "afcount")
        longs: dict[str, list] = {name: [] for name in names}
        reals: dict[str, list] = {name: [] for name in ("pmap", "length", "poly", "turn",
                                                        "offset", "state")}
        longs["pptr"].append(0)
        first, work = 0, 0
        for block in h.blocks:
            if isinstance(block, SlidingBlock):
                line, p = block.line, block.point_size
                kl = p + line.ndof
                free = model.free_position[block.dofs] >= 0
                rank = np.cumsum(free) - 1            # place among the block's free columns
                longs["row"].append(first)
                longs["pmapptr"].append(len(reals["pmap"]))
                longs["pdof"].extend(block.dofs[:p])
                longs["pptr"].append(len(longs["pdof"]))
                reals["pmap"].extend(block.point_map.ravel())
                longs["elements"].append(line.elements)
                longs["ndof"].append(line.ndof)
                longs["edofptr"].append(len(longs["edof"]))
                longs["edof"].extend(block.dofs[block.element_columns].ravel())
                reals["length"].append(line.length)
                longs["polyptr"].append(len(reals["poly"]))
                reals["poly"].extend(line.polynomials.ravel())
                longs["nptr"].append(len(longs["order"]))
                for normal in block.normals:
                    longs["order"].append(normal.order)
                    reals["turn"].extend(normal.turn.ravel())
                    reals["offset"].extend(normal.offset)
                reals["state"].extend(block.start)
                longs["afstart"].append(offset + int(h.free_indptr[first]))
                longs["afcount"].append(int(h.free_indptr[first + block.rows]
                                            - h.free_indptr[first]))
                longs["afptr"].append(len(longs["af"]))
                longs["targetptr"].append(len(longs["target"]))
                for element in range(line.elements):
                    columns = block.element_coordinates(element)
                    for r in range(block.rows):
                        start = offset + int(h.free_indptr[first + r])
                        longs["af"].extend(np.where(free[columns], start + rank[columns],
                                                    -1))
                    dofs = block.dofs[columns]
                    if sparse:
                        longs["target"].extend(model.slots(dofs).ravel())
                    else:
                        place = model.free_position[dofs]
                        rows, cols = np.meshgrid(place, place, indexing="ij")
                        keep = (rows >= 0) & (cols >= 0) & (rows <= cols)
                        longs["target"].extend(np.where(keep, cols * ld + bw + rows - cols,
                                                        -1).ravel())
                work = max(work, 4 * line.ndof + 10 * kl + 4 * kl * kl + 9 * 3 * kl)
            first += block.rows
        m.nsliding = len(longs["row"])
        for name, values in longs.items():
            setattr(m, f"sl_{name}", self._buffer(np.array(values, np.int64), "long"))
        for name, values in reals.items():
            setattr(m, f"sl_{name}", self._buffer(np.array(values, float)))
        self._sliding_failure = np.zeros(3)
        m.sl_failure = self._buffer(self._sliding_failure)
        m.sl_work = self._work(work)

    def _sliding_failed(self) -> SlideError | None:
        """The sliding joint failure of the step's last evaluation of the rows, if any."""
        if not hasattr(self, "_sliding_failure") or not self._sliding_failure[0]:
            return None
        kind, joint, parameter = self._sliding_failure
        self._sliding_failure[:] = 0.0
        block = sliding_blocks(self.dae)[int(joint)]
        if kind == 3:
            return SlideError(no_closest_point(block.owner))
        return SlideError(left_the_body(block.owner, "end" if kind == 2 else "start",
                                        parameter, block.line))

    def raise_callback_error(self) -> None:
        """Raise what a follower load's evaluation raised during the last call, if any."""
        error, self._callback_error = getattr(self, "_callback_error", None), None
        if error is not None:
            raise error

    def _kkt(self, m, rows: scipy.sparse.csr_matrix) -> None:
        """Bind the KKT system of the joints' rows ``rows`` (the step's constraint CSR, whose
        entry order the slots follow): its pattern, slots, CHOLMOD analysis and buffers."""
        system = linear.KKTSystem(self.dae.model.pattern, rows,
                                  refinements=linear.ITERATION_KKT_REFINEMENTS)
        self._kkt_system = system             # CHOLMOD's analysis lives as long as the step
        pattern, total = system.pattern, system.n + system.m
        m.kkt_nnz = pattern.nnz
        m.kkt_indptr = self._buffer(pattern.indptr, "int")
        m.kkt_indices = self._buffer(pattern.indices, "int")
        for name in ("s_slots", "below_slots", "above_slots", "diagonal_slots", "s_diagonal"):
            setattr(m, f"kkt_{name}", self._buffer(getattr(system, name), "int"))
        m.kkt_diagonal_count = system.s_diagonal.size
        self._bind_kkt(m.kkt, system)
        for name in ("rhs", "solution", "correction"):
            setattr(m, f"kkt_{name}", self._work(total))
        m.kkt_regularisation = linear.KKT_REGULARISATION

    def _projection(self, m, rows: scipy.sparse.csr_matrix, ld: int) -> None:
        """Bind what the step's trapezoidal projection onto nonlinear rows (``project``)
        factorises: the mass matrix's band (``ld`` rows a column) or its own CHOLMOD analysis
        of the pattern (its values M_ff, factorised by the step's first projection) and
        the buffers of its Schur complement of the rows; with the KKT system, a second
        ``KKTSystem`` of the rows ``rows`` for [[M, C^T], [C, -delta I]]."""
        nf, nj, pattern = self.dae.free.size, self.dae.constraint_rows, self.dae.model.pattern
        if self.kkt:
            self._kkt_mass_system = linear.KKTSystem(pattern, rows)
            self._bind_kkt(m.kkt_mass, self._kkt_mass_system)
            return
        mass = m.mass
        mass.kind = 0
        if self.linear_solver == "sparse":
            cholesky = self._mass_cholesky = cholmod.Cholesky(pattern)
            cholesky.values[:] = linear.pattern_values(self.dae.mass_ff, pattern)
            self._bind_cholmod(mass, cholesky, "cholmod_")
        else:
            mass.band = self._work(nf * ld)
        mass.coupling = self._work(nf * nj)
        mass.schur = self._work(nj * nj)
        mass.schur_pivots = self._work(nj, "int")

    def _bind_kkt(self, target, system: linear.KKTSystem) -> None:
        """Bind a KKT matrix (``ancf_kkt``): the values and analysis of ``system``'s
        CHOLMOD object and its refinements."""
        target.values = self._ffi.from_buffer("double[]", system.cholesky.values)
        target.refinements = system.refinements
        self._bind_cholmod(target, system.cholesky)

    def _bind_cholmod(self, target, cholesky, prefix: str = "") -> None:
        """Bind the CHOLMOD objects of ``cholesky`` (matrix, factor, common, handles) to the
        fields ``prefix`` + name of the step's struct ``target``."""
        for name in ("matrix", "factor", "common", "handles"):
            setattr(target, prefix + name,
                    self._ffi.cast("void *", cholmod.address(getattr(cholesky, name))))
        if cholesky.source is not None:     # analysed in its factor's order (Cholesky)
            permutation = self._ffi.new("ancf_permutation *")
            permutation.entries = cholesky.source.size
            permutation.source = self._buffer(cholesky.source, "int")
            permutation.perm = self._buffer(cholesky.perm, "int")
            permutation.values = self._ffi.from_buffer("double[]", cholesky.values)
            permutation.permuted = self._ffi.from_buffer("double[]", cholesky.permuted)
            permutation.work = self._work(cholesky.n * max(self.dae.constraint_rows, 1))
            self._keep.append(permutation)
            setattr(target, prefix + "permutation", permutation)

    def _sparse(self, m) -> None:
        """Bind the sparse solver: the pattern, the mass at its entries, CHOLMOD's analysis
        and functions, and SuperLU through callbacks for matrices not positive definite."""
        solver, pattern, ffi = self.linear, self.dae.model.pattern, self._ffi
        cholesky = solver.cholesky
        m.nnz = pattern.nnz
        m.pattern_indptr = self._buffer(pattern.indptr, "int")
        m.pattern_indices = self._buffer(pattern.indices, "int")
        m.mass_values = self._buffer(linear.pattern_values(self.dae.mass_ff, pattern))
        m.values = ffi.from_buffer("double[]", cholesky.values)   # CHOLMOD reads these
        self._bind_cholmod(m, cholesky, "cholmod_")
        for name, address in cholmod.functions().items():
            setattr(m, name, ffi.cast("void *", address))
        nf, lu = pattern.shape[0], {}

        def lu_factor() -> int:
            try:
                lu["factor"] = linear.superlu(pattern, cholesky.values)
            except np.linalg.LinAlgError:
                return -1
            return 0

        def lu_solve(x, columns: int) -> int:
            block = np.frombuffer(ffi.buffer(x, 8 * nf * columns)).reshape(columns, nf)
            block[:] = lu["factor"].solve(np.ascontiguousarray(block.T)).T
            return 0

        # the callback objects themselves are kept alive (what the struct's fields read
        # back is a bare pointer to them)
        callbacks = [ffi.callback("int(void)", lu_factor, error=-1),
                     ffi.callback("int(double *, long)", lu_solve, error=-1)]
        m.lu_factor, m.lu_solve = callbacks
        self._keep += callbacks

    def _block_chunks(self) -> int:
        """Chunks of elements in a block (the kernels of one block run while the block
        before is added): 1 on one thread."""
        return 1 if self.threads == 1 else self.threads * BLOCK_CHUNKS_PER_THREAD

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
        chunks = min(elements, CHUNK) * 2 * self._block_chunks()   # two blocks' buffers
        target.e = self._work(chunks * ndof)
        target.force = self._work(chunks * ndof)
        target.jacobian = self._work(chunks * ndof * ndof)
        if self.linear_solver == "sparse":
            target.slots = self._buffer(self.dae.model.slots(group.dofs), "int")
        if element.damping > 0:
            damping = element.kind.families[element.damping_family]
            self._inputs(target, "damping_", _input_slots(damping, DAMPING),
                         element.damping_inputs)
            family = element.damping_kernel_family
            for kernel in DAMPING:
                setattr(target, f"{kernel}_kernel",
                        self._ffi.cast("void *", family.address(kernel)))
            target.e_dot = self._work(chunks * ndof)
            target.force_damping = self._work(chunks * ndof)
            target.jacobian_dot = self._work(chunks * ndof * ndof)

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
        s.probe = 1
        return s

    # --- the loop ----------------------------------------------------------------------

    def run(self, t_end: float, step: float, observe=None, progress=None, *,
            observe_block=None):
        """Integrate from rest at t = 0 to ``t_end``, as the Python engine: the states at
        t = 0 and every ``output_every`` seconds go to ``observe(t, q_full, v_full)`` one by
        one, or to ``observe_block(times, q_full, v_full, dissipated, angles)`` in blocks of
        output times (k,), (k, size), (k, size), (k,), (k, loads) (the torsional springs'
        joint angles, turns counted: ``StateLoads.spring_angles``): several output times per
        call of the compiled step, so an output costs no call of its own.  Raises Divergence (the
        outputs before it observed)."""
        observe_block = observe_block or one_by_one(observe, self.dae.model)
        with single_threaded_blas():
            return self._run(t_end, step, observe_block, progress)

    def _run(self, t_end: float, step: float, observe_block, progress) -> State:
        dae = self.dae
        dae.state_loads.reset_turns()      # a run counts turns afresh (in Python and in C)
        state = initial_state(dae, mass=self.mass)
        m, self._prepared = self._prepared, None
        if m is None or m.h != step:
            m = self._model(step)
        s = self._state(state)
        turned = self._turned(m)
        turned[:] = 0.0
        every = self.settings.output_every or step
        steps = int(round(t_end / step))
        stride = max(1, int(round(every / step)))
        self._emit(observe_block, np.zeros(1), state.q[None, :], state.v[None, :],
                   np.zeros(1), turned[None, :])
        outputs = 1      # output times per call: sized by the time the calls take
        first = 1
        try:
            while first <= steps:
                last = min(steps, ((first - 1) // stride + outputs) * stride)
                seconds = s.advance_seconds
                done = self._advance(m, s, first, last, stride, steps, step, observe_block)
                if progress is not None:
                    progress.update(done * step)
                per_output = stride * (s.advance_seconds - seconds) / max(1, done - first + 1)
                outputs = int(min(MAX_BLOCK_OUTPUTS, max(1.0, BLOCK_SECONDS
                                                          / max(per_output, 1e-9))))
                first = last + 1
        finally:
            self._sync(s)
        arrays = self._state_arrays
        extra = {"dissipated": s.dissipated, "power": s.power}
        if self.integrator == "generalized_alpha":
            extra["abar"] = arrays[4]
        return State(steps * step, arrays[0], arrays[1], arrays[2], arrays[3], extra)

    def _advance(self, m, s, first: int, last: int, stride: int, steps: int, step: float,
                 observe_block) -> int:
        """Steps ``first`` .. ``last`` in one call; observes their output times; returns the
        last step done.  Raises Divergence after observing the outputs before it."""
        dae = self.dae
        times = np.arange(first, last + 1) * step
        try:
            block = [*dae.prescribed_motion(times), dae.load_factors(times)]
        except LoadFunctionError as error:   # a Python time law failed in this block
            raise Divergence(float(times[0]), str(error)) from None
        numbers = np.arange(first, last + 1)
        output_steps = numbers[(numbers % stride == 0) | (numbers == steps)]
        nf = dae.free.size
        out_q, out_v = (np.empty((output_steps.size, nf)) for _ in range(2))
        out_dissipated = np.empty(output_steps.size)
        out_turned = np.empty((output_steps.size, len(dae.state_loads.compiled)))
        before = s.steps
        status = self._lib.ancf_advance(m, s, first, last - first + 1,
                                        *map(self._block_array, block), stride, steps,
                                        *map(self._block_array,
                                             (out_q, out_v, out_dissipated, out_turned)))
        self._sync(s)
        failure = None
        try:
            self.raise_callback_error()
        except LoadFunctionError as error:   # a Python load failed at s.failed_at
            failure = Divergence(s.failed_at, str(error))
        slide = self._sliding_failed() if status else None
        if slide is not None:                # a sliding joint's point left its body
            failure = Divergence(s.failed_at, str(slide))
        done = first - 1 + (s.steps - before)
        written = int(np.count_nonzero(output_steps <= done))
        if written:
            rows = output_steps[:written] - first
            self._emit(observe_block, output_steps[:written] * step, out_q[:written],
                       out_v[:written], out_dissipated[:written], out_turned[:written],
                       (block[0][rows], block[1][rows]))
        if failure is not None:
            raise failure
        if status:
            raise Divergence(s.failed_at, self._cause(status, s))
        return done

    def _emit(self, observe_block, times: np.ndarray, q_free: np.ndarray, v_free: np.ndarray,
              dissipated: np.ndarray, turned: np.ndarray,
              prescribed: tuple | None = None) -> None:
        """Observe a block of output states given over the free coordinates, with the
        force elements' ``turned`` (k, elements: fe_turned); ``prescribed``: the prescribed
        values and rates at ``times`` if known (else computed)."""
        qp, vp = prescribed or self.dae.prescribed_motion(times)[:2]
        q_full = self.dae.full_coordinates(q_free, qp)
        loads = self.dae.state_loads
        near = np.zeros((times.size, loads.scene_loads))
        for element, (index, _, _) in enumerate(loads.compiled):
            near[:, index] = turned[:, element]
        observe_block(times, q_full, self.dae.full_velocities(v_free, vp), dissipated,
                      loads.spring_angles(q_full, near))

    def _turned(self, m) -> np.ndarray:
        """The step's fe_turned (force elements,), a view (empty without them)."""
        count = len(self.dae.state_loads.compiled)
        if not count:
            return np.zeros(0)
        return np.frombuffer(self._ffi.buffer(m.fe_turned, 8 * count))

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
                       "factorisation_s": s.factor_seconds, "solve_s": s.solve_seconds,
                       "constraint_s": s.constraint_seconds}

    def _cause(self, status: int, s) -> str:
        if status == 1:
            return NON_FINITE
        if status == 2:
            return newton_not_converged(self.settings.max_iterations, s.last_correction)
        if status == 4:
            return PROJECTION_FAILED
        return SINGULAR


class CompiledStatic:
    """Newton solves of the static equilibrium through the generated step (``ancf_static``:
    the same kernels, banded assembly, factorisation and joint solve as the dynamic step),
    one call per load increment of ``runtime.solve.static``, with its convergence test
    (``runtime.solve.static.Convergence``).  The module is the one a dynamic analysis with
    ``integrator`` uses (compiled once for both)."""

    def __init__(self, model: Model, settings, integrator: str) -> None:
        binding = Dynamic(t_end=1.0, step=1.0, integrator=integrator,
                          tolerance=settings.tolerance, max_iterations=settings.max_iterations)
        self.engine = CompiledEngine(model, binding, model.reference)
        self.compile_s, self.modules = self.engine.compile_s, self.engine.modules
        dae = self.engine.dae
        self.convergence = Convergence.of(model, settings.tolerance)
        self._m, self.engine._prepared = self.engine._prepared, None
        self._m.newton = NEWTON_MODES.index("full")
        self._m.residual_tolerance = settings.tolerance
        self._m.residual_floor = self.convergence.floor
        rest = np.zeros(dae.free.size)
        self._s = self.engine._state(State(0.0, dae.fixed_values[dae.free], rest, rest,
                                           np.zeros(dae.constraint_rows),
                                           {"dissipated": 0.0, "power": 0.0}))
        self._qp = dae.prescribed_motion([0.0])[0][0]
        self._qp_buffer = self.engine._buffer(self._qp)
        self.max_iterations = settings.max_iterations
        self._turned = self.engine._turned(self._m)

    def __call__(self, q: np.ndarray, load_fraction: float,
                 multipliers: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        """Equilibrium (q_full (size,), multipliers, iterations) under ``load_fraction`` of
        every load, from q_full and multipliers.  Raises ConvergenceError,
        IllConditionedError."""
        dae, s = self.engine.dae, self._s
        state_q, state_lam = self.engine._state_arrays[0], self.engine._state_arrays[3]
        state_q[:] = q[dae.free]
        state_lam[:] = multipliers
        loads = self.engine._buffer(load_factors(dae.model, load_fraction))
        before = s.newton_iterations
        status = self.engine._lib.ancf_static(self._m, s, self._qp_buffer, loads)
        self.engine._sync(s)
        self.engine.raise_callback_error()
        if status == 1:
            raise ConvergenceError("static: non-finite residual")
        if status == 2:
            raise self.convergence.not_converged(self.max_iterations, s.last_correction,
                                                 s.last_residual, s.force_scale)
        if status == 3:
            raise ConvergenceError("static: singular iteration matrix")
        self.convergence.check_resolved(s.force_scale)
        return (dae.full_coordinates(state_q.copy(), self._qp), state_lam.copy(),
                s.newton_iterations - before)

    def accept(self, q_full: np.ndarray) -> None:
        """Count the torsional springs' turns up to the converged state q_full (size,), for
        the next solves (``StateLoads.accept``, and the step's fe_turned)."""
        loads = self.engine.dae.state_loads
        loads.accept(q_full)
        for element, (_, evaluate, _) in enumerate(loads.compiled):
            self._turned[element] = getattr(evaluate, "turned", 0.0)

    def spring_angles(self, q_full: np.ndarray) -> np.ndarray:
        """The torsional springs' joint angles at the states q_full (k, size), turns
        counted (``StateLoads.spring_angles``)."""
        return self.engine.dae.state_loads.spring_angles(q_full)

