"""The paper's static cantilever (section 7, Table I) with a plain Newton solve.

L = 5 m, 0.1 x 0.1 m, E = 132 GPa, nu = 0, tip load 300 N: the tip deflection of 2 and 5
beam3d elements is 1.07 and 1.13 cm in Table I (the Euler-Bernoulli value P L^3 / 3EI is
1.136 cm).  Nodes are shared between consecutive elements; the first node is clamped.
"""

import numpy as np
import pytest

from runtime import Element

LENGTH, SIDE, E_MODULUS, LOAD = 5.0, 0.1, 132e9, 300.0


def tip_deflection(elements: int, method: str, backend: str) -> tuple[float, int]:
    """Static tip deflection (m, downward positive) and Newton iterations."""
    element = Element("beam3d", LENGTH / elements, SIDE, SIDE, E_MODULUS, 0.0, 8245.2,
                      method=method, backend=backend)
    per_node = 12
    nodes = elements + 1
    reference = np.concatenate([element.e0[:per_node] + np.r_[LENGTH / elements * i, np.zeros(11)]
                                for i in range(nodes)])
    q = reference.copy()
    external = np.zeros_like(q)
    external[(nodes - 1) * per_node + 1] = -LOAD
    free = np.arange(per_node, q.size)
    index = np.array([np.arange(i * per_node, i * per_node + 2 * per_node)
                      for i in range(elements)])
    for iteration in range(1, 30):
        batch = q[index]
        force = element.elastic_force(batch)
        jacobian = element.elastic_jacobian(batch)
        residual = external.copy()
        tangent = np.zeros((q.size, q.size))
        for i in range(elements):
            residual[index[i]] += force[i]
            tangent[np.ix_(index[i], index[i])] += jacobian[i]
        step = np.linalg.solve(tangent[np.ix_(free, free)], -residual[free])
        q[free] += step
        if np.abs(step).max() < 1e-13 * LENGTH:
            return float(reference[(nodes - 1) * per_node + 1] - q[(nodes - 1) * per_node + 1]), \
                iteration
    raise AssertionError("Newton did not converge")


@pytest.mark.parametrize("method", ["gram", "cij", "quadrature"])
@pytest.mark.parametrize("elements, table_cm", [(2, 1.07), (5, 1.13)])
def test_table_one_tip_deflection(elements, table_cm, method):
    deflection, iterations = tip_deflection(elements, method, "c")
    assert round(deflection * 100, 2) == table_cm
    assert iterations <= 6  # quadratic convergence with the exact Jacobian


def test_deflection_approaches_beam_theory():
    exact = LOAD * LENGTH**3 / (3 * E_MODULUS * SIDE**4 / 12)
    coarse, _ = tip_deflection(2, "gram", "numpy")
    fine, _ = tip_deflection(5, "gram", "numpy")
    assert coarse < fine < exact * 1.001
    assert abs(fine - exact) / exact < 0.01
