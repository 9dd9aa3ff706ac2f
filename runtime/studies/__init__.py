"""Studies and benchmarks over whole runs: the paper's tables, error against run time, numerical
stability, invariant comparisons, kernel and solver benchmarks, side-by-side runs of the peer
code (Exudyn), and the report that gathers them.  Each study keeps its plan, its measurements
and its report apart.

May import: every lower layer (runtime.app, runtime.solve, runtime.model, runtime.element,
runtime.kernels), the public API ``runtime`` and runtime.catalog, runtime.progress.
"""
