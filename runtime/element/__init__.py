"""One ANCF element: ``Element`` (forces, Jacobians, energies, mass of one kind), its invariants
and the reference geometry of elements placed in space.

May import: runtime.kernels, runtime.catalog.
"""
