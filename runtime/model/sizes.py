"""Size estimates of a scene, before anything is built (``LIMITS``): memory of the model
(element matrices, assembly, factorisation) and of a dense modal analysis with joints within
24 GiB; at most 1e8 time steps or load increments and 1e10 element-steps (about a day at the
measured ~9 us per element and step); at most 1e8 values in the time series; at most 1000
Newton iterations, 1000 modes (and no more than the degrees of freedom), 1000 sensors and
Gauss orders up to 64; some coordinate stays free.
"""

from __future__ import annotations

import math

from runtime.kernels.kind import element_kind
from runtime.model.bodies import Body
from runtime.model.errors import SceneError, number_text
from runtime.model.items.constraints import Constraint, NodeConstraint, NodePair
from runtime.model.items.sensors import Sensor
from runtime.model.settings import Dynamic, Modal, Static

LIMITS = {
    "memory_bytes": 24 * 2**30,          # this machine
    "bytes_per_matrix_entry": 256,       # per entry of the element matrices (ndof^2 each):
                                         # measured ~160 B for build + static solve, + margin
    "steps": 10**8,                      # time steps, load increments
    "element_steps": 10**10,             # elements x steps: ~9 us each -> about a day
    "output_values": 10**8,              # rows x columns of timeseries.csv (read back to plot)
    "iterations": 1000,                  # Newton iterations per step
    "threads": 64,                       # threads of the compiled step's kernels
    "modes": 1000,
    "sensors": 1000,                     # one CSV column and one PNG each
    "quadrature": 64,                    # Gauss order per direction (runtime.element.element)
    "scene_bytes": 16 * 2**20,           # size of a scene file
}


def _big(n: int) -> str:
    return str(n) if n < 10**15 else f"~1e{int(n.bit_length() * math.log10(2))}"


def _gib(n: int) -> str:
    return f"{n / 2**30:.3g} GiB" if n < 10**300 else f"{_big(n // 2**30)} GiB"


def _model_bytes(bodies: tuple[Body, ...]) -> int:
    """Estimated peak memory (bytes) of building and solving the model of the bodies."""
    return LIMITS["bytes_per_matrix_entry"] * sum(
        b.elements * element_kind(b.element).ndof ** 2 for b in bodies)


def _coordinates(bodies: tuple[Body, ...]) -> int:
    """Number of coordinates of the model of the bodies (nodes times coordinates per node)."""
    return sum(b.n_nodes * element_kind(b.element).per_node for b in bodies)


def check_model_size(bodies: tuple[Body, ...]) -> None:
    """Refuse a mesh whose model cannot fit the memory of this machine (``LIMITS``)."""
    memory = LIMITS["memory_bytes"]
    per_entry = LIMITS["bytes_per_matrix_entry"]
    ndof = {b.name: element_kind(b.element).ndof for b in bodies}
    entries = [b.elements * ndof[b.name] ** 2 for b in bodies]
    elements = sum(b.elements for b in bodies)
    coordinates = _coordinates(bodies)
    model_bytes = _model_bytes(bodies)
    if model_bytes > memory:
        i = max(range(len(bodies)), key=entries.__getitem__)
        n = ndof[bodies[i].name]
        most = memory // (per_entry * n * n)
        key = bodies[i].placement.count_key
        raise SceneError(f"body[{i}].{key}: {_big(elements)} elements ({_big(coordinates)} "
                         f"coordinates) need about {_gib(model_bytes)} of memory (estimate: "
                         f"{per_entry} B per entry of the {n}x{n} element matrices), over the "
                         f"limit of {_gib(memory)}; expected at most about {most} "
                         f"{bodies[i].element} elements in the scene")


def check_sizes(bodies: tuple[Body, ...], constraints: tuple[Constraint, ...],
                 sensors: list[Sensor], static: Static | None, modal: Modal | None,
                 dynamic: Dynamic | None, rigid_coordinates: int = 0) -> None:
    """Refuse what cannot run on this machine in a sane time (``LIMITS``), before building;
    the mesh itself passed ``_check_model_size``; ``rigid_coordinates``: those of the rigid
    bodies and point masses."""
    memory = LIMITS["memory_bytes"]
    elements = sum(b.elements for b in bodies)
    dim = bodies[0].dim if bodies else 3
    kinds = {b.name: element_kind(b.element) for b in bodies}
    coordinates = _coordinates(bodies) + rigid_coordinates
    model_bytes = _model_bytes(bodies)
    held = sum(c.held(kinds[node.body]) for c in constraints
               if isinstance(c, NodeConstraint) for node in c.targets())
    free = coordinates - held
    joints = [c for c in constraints if isinstance(c, NodePair)]
    dofs = free - sum(c.rows(dim, kinds[c.nodes[0].body].per_node) for c in joints)
    if dofs <= 0:
        raise SceneError(f"constraint: the constraints hold all {coordinates} coordinates of "
                         f"the model; expected at least one free coordinate")
    if modal is not None:
        if modal.modes > dofs:
            raise SceneError(f"analysis.modal.modes: expected at most the {dofs} degrees of "
                             f"freedom of the model, got {modal.modes}")
        dense = 24 * free**2 if joints else 0
        if model_bytes + dense > memory:
            raise SceneError(f"analysis.modal: with joints, a modal analysis works on dense "
                             f"{free}x{free} matrices: about {_gib(model_bytes + dense)} with "
                             f"the model, over the limit of {_gib(memory)}; expected fewer "
                             f"elements, no joints or no modal analysis")

    work = LIMITS["element_steps"]
    if static is not None:
        key, steps, what = (("max_steps", static.max_steps, "path points")
                            if static.method == "arc_length" else
                            ("load_steps", static.load_steps, "load increments"))
        if steps * elements > work:
            raise SceneError(f"analysis.static.{key}: {steps} {what} of {elements} elements "
                             f"exceed the limit of {work:.0e} element-steps (about a day); "
                             f"expected at most {work // elements} {what}")
    if dynamic is not None:
        steps = round(dynamic.t_end / dynamic.step)
        if steps * elements > work:
            raise SceneError(f"analysis.dynamic.step: {steps} time steps of {elements} elements "
                             f"exceed the limit of {work:.0e} element-steps (about a day at "
                             f"~9 us per element and step); expected step >= "
                             f"{number_text(dynamic.t_end * elements / work)} s, a shorter "
                             f"t_end or fewer elements")
        every = dynamic.output_every or dynamic.step
        rows = round(dynamic.t_end / every) + 2
        columns = len(sensors) + 1
        if rows * columns > LIMITS["output_values"]:
            what = "output_every" if dynamic.output_every else "output_every (absent: every step)"
            least = dynamic.t_end * columns / LIMITS["output_values"]
            raise SceneError(f"analysis.dynamic.{what}: {rows} rows of {columns} columns in "
                             f"timeseries.csv exceed the limit of {LIMITS['output_values']:.0e} "
                             f"values (the file is read back whole for the plots); expected "
                             f"output_every >= {number_text(least)} s (a multiple of step)")
