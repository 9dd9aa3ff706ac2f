"""Runtime of the ANCF toolchain: generated kernels, elements, models and the CLI."""

from runtime.element import Element

__all__ = ["Element"]
