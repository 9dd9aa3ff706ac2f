"""Force elements between two points: the linear point-to-point spring-damper.

The points are nodes of meshed bodies, points of rigid bodies (or point masses), or a fixed
anchor; each position is linear in its coordinates, so with x = q[dofs] (k,) the vector
between them is ``d = D x + d_0`` (D (3, k) constant, d_0 the anchor).  With L = |d|,
n = d / L and the rate L' = n . D x', the force along the element is
``f = k (L - L0) + c L'`` and the generalised force is ``Q = -f D^T n``; its exact Jacobians

    dQ/dx  = -D^T [k n n^T + c n (D x' - n L')^T / L + f (I - n n^T) / L] D,
    dQ/dx' = -c D^T n n^T D

(``SpringDamperForce``; both engines evaluate it as a state load, ``runtime.model.dae``).
"""

from __future__ import annotations

import numpy as np

from runtime.model.items.python_loads import MotionPatches

__all__ = ["SpringDamperForce"]


class SpringDamperForce:
    """The state force of a spring-damper of ``stiffness`` k (N/m), ``damping`` c (N s/m) and
    rest length ``length`` L0 (m) over the coordinates ``dofs`` (k,), with the map
    ``difference`` D (3, k) and the constant ``offset`` d_0 (3,) of d = D x + d_0.  Reads
    velocities (``reads_velocity``)."""

    reads_velocity = True

    def __init__(self, dofs: np.ndarray, difference: np.ndarray, offset: np.ndarray,
                 stiffness: float, damping: float, length: float) -> None:
        self.dofs = np.asarray(dofs, np.int64)[None, :]
        self.difference, self.offset = difference, np.asarray(offset, float)
        self.stiffness, self.damping, self.length = stiffness, damping, length

    def vector(self, q: np.ndarray) -> np.ndarray:
        """d (3,) at the coordinates q (size,)."""
        return self.difference @ q[self.dofs[0]] + self.offset

    def __call__(self, q: np.ndarray, jacobian: bool, v: np.ndarray | None = None,
                 t: float = 0.0) -> MotionPatches:
        dofs = self.dofs[0]
        D = self.difference
        d = self.vector(q)
        length = float(np.linalg.norm(d))
        if length == 0.0:
            raise ZeroDivisionError("a spring-damper of zero length has no direction")
        n = d / length
        rate_vector = np.zeros(3) if v is None else D @ v[dofs]
        rate = float(n @ rate_vector)
        f = self.stiffness * (length - self.length) + self.damping * rate
        force = -f * (D.T @ n)
        if not jacobian:
            return MotionPatches(self.dofs, force[None], None, None)
        across = (np.eye(3) - np.outer(n, n)) / length
        inner = (self.stiffness * np.outer(n, n)
                 + self.damping * np.outer(n, rate_vector - n * rate) / length + f * across)
        d_q = -D.T @ inner @ D
        d_v = -self.damping * D.T @ np.outer(n, n) @ D
        return MotionPatches(self.dofs, force[None], d_q[None], d_v[None])
