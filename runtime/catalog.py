"""Names of the interchangeable parts of a run, the only lists of them (scene validation,
CLI choices and registries read them from here, so a new part is added in one place)."""

#: Dynamic engines (registry: ``runtime.solve.engines.ENGINES``).
ENGINES = ("compiled", "python")
#: Newton modes of the dynamic integrators (both engines).
NEWTON_MODES = ("full", "modified")
