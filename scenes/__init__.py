"""The scenes shipped with the project (TOML files), installed as package data."""

from pathlib import Path


def path(name: str) -> Path:
    """The shipped scene ``name`` (without ``.toml``), e.g. ``path("cantilever")``."""
    return Path(__file__).resolve().parent / f"{name}.toml"


def names() -> list[str]:
    """Names of every shipped scene, sorted."""
    return sorted(p.stem for p in Path(__file__).resolve().parent.glob("*.toml"))
