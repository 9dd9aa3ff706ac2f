"""The items of a scene, one registry per kind of item: constraints, loads, sensors.  Each item
declares its TOML keys (``runtime.model.schema.Record``), its checks and its contribution to a
model through the narrow interface of ``runtime.model.items.base``; items never import the model.

May import: runtime.model.schema, runtime.model.time_laws, runtime.model.errors,
runtime.element, runtime.kernels, runtime.catalog.
"""
