"""Deformed shapes of a model: the beams' centre lines, ParaView files, an animation.

The centre line of an element is ``r(x) = S(x) e`` at local points ``(x, 0[, 0])``, with the
shape functions ``S`` of the element kind (the generated ``shape_values`` kernel of its
invariants family); ``CentreLine`` samples it a few points per element, so displacements,
velocities and mode shapes (all linear in the coordinates) are sampled the same way.

Writers (all atomic, a write error is :class:`runtime.output.OutputError`):

* :func:`write_vtu` - one VTU file (meshio): the centre lines as line cells, point data
  ``displacement`` (m) and ``velocity`` (m/s), or any vectors given;
* :func:`write_pvd` - a ParaView collection of VTU files with their times;
* :class:`VtkSeries` - a run observer writing ``vtk/dynamic_NNNNNN.vtu`` at every output time
  and ``vtk/dynamic.pvd``, plus ``vtk/static.vtu`` and ``vtk/mode_K.vtu`` / ``vtk/modes.pvd``;
* :class:`Frames` (a run observer) and :func:`write_animation` - a GIF of the deformed shape
  projected on a plane; :func:`write_snapshot` - a PNG of one state against the reference.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from runtime import output
from runtime.kernels import kernel_family
from runtime.model import Model
from runtime.progress import Bar
from runtime.result import Modes, Observer

__all__ = ["PLANES", "CentreLine", "Frames", "VtkSeries", "magnification", "write_animation",
           "write_pvd", "write_snapshot", "write_vtu"]

#: sample points per element along each centre line
PER_ELEMENT = 4
#: projections of the animation and snapshot: plane name -> (horizontal, vertical) axes
PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
#: frames of an animation at most (output times are subsampled evenly beyond)
MAX_FRAMES = 100


class CentreLine:
    """The centre lines of every body of ``model``, ``per_element`` segments per element.

    ``points``: number of sample points (bodies one after the other, each from its node 0);
    ``segments``: (points - bodies, 2) point indices of the line cells; ``node_points``:
    index of the sample point at each model node (node-major order of the model).
    """

    def __init__(self, model: Model, per_element: int = PER_ELEMENT) -> None:
        self.model, self.dim = model, model.dim
        self._bodies = []   # (element dofs (m, ndof), shape values (s + 1, n_shape))
        segments, node_points, first = [], [], 0
        for body in model.bodies.values():
            element = body.element
            length = element.geometry[0]
            points = np.zeros((per_element + 1, element.kind.dim))
            points[:, 0] = np.linspace(0.0, length, per_element + 1)
            family = kernel_family(element.kind.name, "invariants", element.backend)
            values = family("shape_values", {"point": points,
                                             "geometry": np.asarray(element.geometry)})["values"]
            self._bodies.append((body.element_dofs, values))
            count = body.elements * per_element + 1
            index = first + np.arange(count - 1)
            segments.append(np.column_stack([index, index + 1]))
            node_points.append(first + per_element * np.arange(body.nodes))
            first += count
        self.points = first
        self.segments = np.concatenate(segments)
        self.node_points = np.concatenate(node_points)

    def sample(self, q: np.ndarray) -> np.ndarray:
        """(points, 3) centre-line vectors of coordinates ``q`` (size,): positions for
        positions, velocities for velocities (z = 0 in 2D)."""
        lines = []
        for dofs, values in self._bodies:
            e = q[dofs].reshape(dofs.shape[0], values.shape[1], self.dim)
            samples = np.einsum("pk,mkd->mpd", values, e)       # (elements, s + 1, dim)
            lines += [samples[:, :-1].reshape(-1, self.dim), samples[-1, -1:]]
        result = np.zeros((self.points, 3))
        result[:, :self.dim] = np.concatenate(lines)
        return result


def write_vtu(path: str | Path, line: CentreLine, q: np.ndarray,
              vectors: dict[str, np.ndarray]) -> Path:
    """The centre lines at coordinates ``q`` into the VTU file ``path``, with point data
    ``{name: (points, 3)}`` (e.g. displacement in m, velocity in m/s)."""
    import meshio

    mesh = meshio.Mesh(line.sample(q), [("line", line.segments)], point_data=vectors)
    path = Path(path)
    with output.atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return path


def write_pvd(path: str | Path, entries: Sequence[tuple[float, str]]) -> Path:
    """A ParaView collection ``path`` of (time, file name relative to it) entries."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    path = Path(path)
    try:
        with output.atomic_file(path, "w") as f:
            f.write("\n".join(lines))
    except OSError as error:
        raise output.OutputError(f"{path}: cannot write ({error.strerror or error})") from None
    return path


class VtkSeries(Observer):
    """Writes a run's shapes into ``folder`` (``vtk/`` of the run folder) as they are
    computed: ``static.vtu``, ``mode_K.vtu`` (point data ``mode``, the mode shape normalised
    to a largest nodal displacement of 1, at the linearisation point) with ``modes.pvd``
    (time = mode number), ``dynamic_NNNNNN.vtu`` at every output time with ``dynamic.pvd``
    (written when the dynamic analysis ends, however it ends).  ``files``: the static file
    and the collections written, as ``<folder name>/<file>``."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.files: list[str] = []
        self._entries: list[tuple[float, str]] = []

    def begin(self, model: Model) -> None:
        self.line = CentreLine(model)
        self.reference = model.reference
        self.zero = np.zeros((self.line.points, 3))
        try:
            self.folder.mkdir(exist_ok=True)
        except OSError as error:
            raise output.OutputError(f"{self.folder}: cannot create the folder "
                                     f"({error.strerror or error})") from None

    def _write(self, name: str, q: np.ndarray, vectors: dict[str, np.ndarray]) -> None:
        write_vtu(self.folder / name, self.line, q, vectors)

    def _collection(self, name: str, entries: list[tuple[float, str]]) -> None:
        write_pvd(self.folder / name, entries)
        self.files.append(f"{self.folder.name}/{name}")

    def static(self, q: np.ndarray) -> None:
        self._write("static.vtu", q, {"displacement": self.line.sample(q - self.reference),
                                      "velocity": self.zero})
        self.files.append(f"{self.folder.name}/static.vtu")

    def modal(self, modes: Modes) -> None:
        entries = []
        for k, shape in enumerate(modes.shapes, start=1):
            name = f"mode_{k}.vtu"
            self._write(name, modes.about, {"mode": self.line.sample(shape)})
            entries.append((float(k), name))
        self._collection("modes.pvd", entries)

    def sample(self, t: float, q: np.ndarray, v: np.ndarray, values: dict[str, float]) -> None:
        name = f"dynamic_{len(self._entries):06d}.vtu"
        self._write(name, q, {"displacement": self.line.sample(q - self.reference),
                              "velocity": self.line.sample(v)})
        self._entries.append((t, name))

    def dynamic_end(self) -> None:
        if self._entries:
            self._collection("dynamic.pvd", self._entries)


class Frames(Observer):
    """Keeps the centre line (points, 3) at the output times of the dynamic analysis, for
    :func:`write_animation`: ``times``, ``frames`` and the ``reference`` line.  Memory stays
    bounded: beyond ``2 * MAX_FRAMES`` frames every other one is dropped (evenly spaced
    output times are kept, and always the latest)."""

    def __init__(self) -> None:
        self.times: list[float] = []
        self.frames: list[np.ndarray] = []
        self._outputs: list[int] = []   # output number of each frame kept
        self._stride = 1                # frames kept: every stride-th output, and the latest
        self._count = 0

    def begin(self, model: Model) -> None:
        self.line = CentreLine(model)
        self.reference = self.line.sample(model.reference)

    def sample(self, t: float, q: np.ndarray, v: np.ndarray, values: dict[str, float]) -> None:
        if self._outputs and self._outputs[-1] % self._stride:  # the latest, not on stride
            self._drop(len(self._outputs) - 1)
        self.times.append(t)
        self.frames.append(self.line.sample(q))
        self._outputs.append(self._count)
        self._count += 1
        if len(self.frames) > 2 * MAX_FRAMES:
            self._stride *= 2
            for k in reversed(range(len(self._outputs) - 1)):
                if self._outputs[k] % self._stride:
                    self._drop(k)

    def _drop(self, k: int) -> None:
        del self.times[k], self.frames[k], self._outputs[k]


def magnification(reference: np.ndarray, states: Sequence[np.ndarray]) -> float:
    """Scale of the displacements drawn: 1 when the largest displacement of ``states``
    (each (points, 3), like ``reference``) is at least 5 % of the model's extent, else the
    1-2-5 factor that shows it as about 10 % (a small static deflection stays visible)."""
    extent = float(np.ptp(reference, axis=0).max()) or 1.0
    largest = max((float(np.abs(s - reference).max()) for s in states), default=0.0)
    if largest == 0.0 or largest >= 0.05 * extent:
        return 1.0
    wanted = 0.1 * extent / largest
    power = 10.0 ** np.floor(np.log10(wanted))
    return float(max(m * power for m in (1, 2, 5) if m * power <= wanted))


def _axes(fig, plane: str, reference: np.ndarray, shown: Sequence[np.ndarray]):
    """An axes of ``fig`` for ``plane`` with limits holding every line, equal scales."""
    i, j = PLANES[plane]
    everything = np.concatenate([reference, *shown])
    low, high = everything.min(axis=0), everything.max(axis=0)
    margin = 0.05 * float(max(high[i] - low[i], high[j] - low[j]) or 1.0)
    ax = fig.add_subplot()
    ax.set_xlim(low[i] - margin, high[i] + margin)
    ax.set_ylim(low[j] - margin, high[j] + margin)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{plane[0]} (m)")
    ax.set_ylabel(f"{plane[1]} (m)")
    ax.grid(True, alpha=0.3)
    ax.plot(reference[:, i], reference[:, j], "--", color="0.6", lw=1, label="reference")
    return ax


def _heading(title: str, what: str, scale: float) -> str:
    """Two title lines: the scene title (cut to 60 characters), then what is drawn."""
    short = title if len(title) <= 60 else title[:57] + "..."
    return f"{short}\n{what}" + (f", displacements x{scale:g}" if scale != 1 else "")


def _check_plane(plane: str) -> tuple[int, int]:
    if plane not in PLANES:
        raise ValueError(f"plane: expected one of {', '.join(PLANES)}, got {plane!r}")
    return PLANES[plane]


def write_snapshot(path: str | Path, line: CentreLine, reference: np.ndarray, q: np.ndarray,
                   title: str, what: str = "static state", plane: str = "xy") -> Path:
    """PNG of the centre line at ``q`` over the reference ``reference`` (coordinates, size,)
    projected on ``plane``, titled ``title`` and ``what``; displacements magnified as
    :func:`magnification` says."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    i, j = _check_plane(plane)
    base = line.sample(reference)
    scale = magnification(base, [line.sample(q)])
    shown = base + scale * (line.sample(q) - base)
    fig = Figure(figsize=(6.4, 4.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = _axes(fig, plane, base, [shown])
    ax.plot(shown[:, i], shown[:, j], lw=2, color="C0", label="deformed")
    ax.set_title(_heading(title, what, scale), fontsize=9)
    ax.legend(fontsize=8)
    path = Path(path)
    with output.atomic_file(path) as f:
        fig.savefig(f, format="png", dpi=100)
    return path


def write_animation(path: str | Path, frames: Frames, title: str, plane: str = "xy",
                    fps: int = 10) -> Path:
    """GIF of the centre lines of ``frames`` projected on ``plane`` (at most ``MAX_FRAMES``
    frames, evenly chosen, the last included), with the reference dashed and the time in
    the title; displacements magnified as :func:`magnification` says."""
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    i, j = _check_plane(plane)
    if not frames.frames:
        raise ValueError("animation: no output time to draw")
    count = len(frames.frames)
    chosen = np.unique(np.linspace(0, count - 1, min(count, MAX_FRAMES)).round().astype(int))
    base = frames.reference
    scale = magnification(base, [frames.frames[k] for k in chosen])
    shown = [base + scale * (frames.frames[k] - base) for k in chosen]
    fig = Figure(figsize=(6.4, 4.0))
    FigureCanvasAgg(fig)
    ax = _axes(fig, plane, base, shown)
    (curve,) = ax.plot(shown[0][:, i], shown[0][:, j], lw=2, color="C0")
    ax.set_title(_heading(title, "dynamic analysis", scale), fontsize=9)
    clock = ax.text(0.02, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    fig.set_layout_engine("constrained")
    fig.canvas.draw()               # lay out once: the frames keep that layout (fast)
    fig.set_layout_engine("none")

    def draw(n: int):
        curve.set_data(shown[n][:, i], shown[n][:, j])
        clock.set_text(f"t = {frames.times[chosen[n]]:.4g} s")
        return curve, clock

    animation = FuncAnimation(fig, draw, frames=len(shown), blit=False)
    path = Path(path)
    with output.atomic_path(path) as tmp, Bar("animation", len(shown), "frames") as bar:
        animation.save(tmp, writer=PillowWriter(fps=fps), dpi=80,
                       progress_callback=lambda done, total: bar.update(done + 1))
    return path
