"""Runs of scenes: the simulation (``run_scene`` -> ``Result``, the typed summary), the writers
(summary, time series, plots), shapes for ParaView and drawings, and ``ancf run``.

May import: runtime.solve, runtime.model, runtime.element, runtime.kernels, runtime.catalog,
runtime.progress.
"""
