"""Solvers of a model: linear algebra, static and modal analyses, the Python and the compiled
dynamic engines and their registry.

May import: runtime.model, runtime.element, runtime.kernels, runtime.catalog, runtime.progress.
"""
