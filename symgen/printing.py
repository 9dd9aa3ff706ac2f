"""One expression printer for both backends.

Kernel expressions only use +, -, *, / and integer powers of array elements, temporaries and
numbers, whose syntax is the same in C and in Python; numbers are printed as round-trip float
literals so the output does not depend on SymPy's printers.
"""

from __future__ import annotations

import sympy as sp


def number(value: sp.Expr) -> str:
    """A float literal that reads back to the same double."""
    text = repr(float(value))
    return text if any(ch in text for ch in ".en") else text + ".0"


def code(expr: sp.Expr) -> str:
    """Source text of ``expr``."""
    expr = sp.sympify(expr)
    if expr.is_Symbol:
        return expr.name
    if expr.is_Number:
        text = number(expr)
        return f"({text})" if text.startswith("-") else text
    if expr.is_Add:
        parts: list[str] = []
        for term in expr.args:
            coeff, _ = term.as_coeff_Mul()
            if parts and coeff.is_negative:
                parts.append(" - " + _factor(-term))
            elif parts:
                parts.append(" + " + _factor(term))
            else:
                parts.append(_factor(term) if not coeff.is_negative else "-" + _factor(-term))
        return "".join(parts)
    if expr.is_Mul:
        coeff, rest = expr.as_coeff_mul()
        factors = [_power_or_atom(f) for f in rest]
        if coeff == -1:
            return "-" + "*".join(factors)
        if coeff != 1:
            factors.insert(0, number(coeff) if coeff > 0 else f"({number(coeff)})")
        return "*".join(factors)
    if expr.is_Pow:
        return _power_or_atom(expr)
    raise TypeError(f"cannot print {type(expr).__name__} in a kernel: {expr}")


def _factor(expr: sp.Expr) -> str:
    """A term of a sum (a product binds tighter than +, so no parentheses needed)."""
    return code(expr)


def _power_or_atom(expr: sp.Expr) -> str:
    if expr.is_Pow:
        base, exponent = expr.args
        if not exponent.is_Integer:
            raise TypeError(f"only integer powers are printable, got {expr}")
        text = "*".join([_power_or_atom(base)] * abs(int(exponent)))
        if exponent < 0:
            return f"(1.0/({text}))"
        return f"({text})" if abs(int(exponent)) > 1 else text
    if expr.is_Add:
        return f"({code(expr)})"
    if expr.is_Number and expr.is_negative:
        return f"({number(expr)})"
    return code(expr)
