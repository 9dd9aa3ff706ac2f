"""Scenes and models: the scene dataclasses, their parsing, checks, size estimates and TOML round
trip; the items of a scene (constraints, loads, sensors) as typed registries; meshes by
connectivity; the assembled ``Model`` and the DAE system the engines consume.

May import: runtime.element, runtime.kernels, runtime.catalog.
"""
