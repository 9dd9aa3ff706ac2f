"""One catalog: every list of names of interchangeable parts (methods, backends, variants,
integrators, engines, Newton modes, material laws, element kinds) is typed only in
``runtime/catalog.py``; every other module takes it from there, and the registries keyed by
these names hold exactly the catalog's names."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from runtime import catalog
from runtime.catalog import family_name
from runtime.kernels.kind import element_kind
from runtime.solve.engines import ENGINES
from runtime.solve.python_engine import INTEGRATORS

ROOT = Path(__file__).resolve().parent.parent
LISTS = {"METHODS": catalog.METHODS, "BACKENDS": catalog.BACKENDS,
         "VARIANTS": catalog.VARIANTS, "INTEGRATORS": catalog.INTEGRATORS,
         "ENGINES": catalog.ENGINES, "NEWTON_MODES": catalog.NEWTON_MODES,
         "BENDING_MODELS": catalog.BENDING_MODELS,
         "material_laws()": catalog.material_laws(),
         "generated_kinds()": tuple(catalog.generated_kinds())}


def _spelled_lists(path: Path, root: Path = ROOT) -> list[str]:
    """Literal tuples, lists and sets of strings in ``path`` that spell two or more names of
    one catalog list."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Tuple | ast.List | ast.Set):
            continue
        strings = {e.value for e in node.elts if isinstance(e, ast.Constant)
                   and isinstance(e.value, str)}
        for name, names in LISTS.items():
            if len(strings & set(names)) >= 2:
                found.append(f"{path.relative_to(root)}:{node.lineno}: {sorted(strings)} "
                             f"(take catalog.{name})")
    return found


def test_no_module_spells_a_list_of_the_catalog():
    sources = [p for p in (ROOT / "runtime").rglob("*.py") if p.name != "catalog.py"]
    assert len(sources) > 40
    found = [line for p in sources for line in _spelled_lists(p)]
    assert not found, "\n".join(found)


def test_the_check_finds_a_spelled_list(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text('METHODS = ("gram", "cij", "quadrature")\nfor law in ["svk", "ecm"]:\n'
                     '    pass\nONE = ("gram", "other")\n')
    assert len(_spelled_lists(probe, tmp_path)) == 2


def test_bending_models_are_the_generators():
    from symgen import energies

    assert catalog.BENDING_MODELS == energies.BENDING_MODELS
    assert {law.bending for law in energies.CABLE_LAWS.values()} == set(catalog.BENDING_MODELS)


def test_registries_hold_the_catalog_names():
    assert tuple(ENGINES) == catalog.ENGINES
    assert tuple(INTEGRATORS) == catalog.INTEGRATORS
    assert catalog.material_laws()[0] == catalog.DEFAULT_LAW


@pytest.mark.parametrize("kind", catalog.generated_kinds())
def test_every_family_the_catalog_names_is_generated(kind):
    families = element_kind(kind).families
    for method in catalog.METHODS:
        for law, info in element_kind(kind).laws.items():
            for variant in info.variants:  # cables: straight only but the planar exact curvature
                for damped in (False, True):
                    assert family_name(method, law, variant, damped, info.bending,
                                       info.structural) in families


def test_family_name_rejects_unknown_names():
    with pytest.raises(ValueError, match="method: expected one of gram, cij, quadrature"):
        family_name("fem", "svk", "straight")
    with pytest.raises(ValueError, match="variant: expected one of straight, general"):
        family_name("gram", "svk", "bent")


def test_the_generator_names_what_the_catalog_names():
    # symgen cannot import the runtime (data flows one way): its own lists must agree
    from symgen import derive, emit

    assert emit.BACKENDS == catalog.BACKENDS
    assert derive.VARIANTS == catalog.VARIANTS
