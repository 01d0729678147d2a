"""Declared layouts of optimal-control vectors: named blocks per stage, indices derived.

An NLP of an optimal control problem stacks its decision variables, constraints and
parameters stage by stage (``[x_0, u_0, s_1, x_1, u_1, s_2, ..., x_N]``). Rather than
hand-computing where each entry lands, a :class:`BlockVector` is *built* from named blocks
(``add("u", stage, expr)``) and answers the index questions afterwards (``index("u")``,
``index("u", 1)``): the order of the vector and its index maps come from one declaration.

The same class serves the decision vector ``w``, the constraint vector ``g`` and the
parameter vector ``p`` of :class:`acid.control.ocp.OCP` (every NMPC of acid).
"""

from __future__ import annotations

import casadi as ca
import numpy as np


class BlockVector:
    """A CasADi column vector assembled from named blocks, one per stage (or unstaged).

    Examples
    --------
    >>> w = BlockVector("w")
    >>> x0 = w.sym("x", 0, 2); u0 = w.sym("u", 0, 2); x1 = w.sym("x", 1, 2)
    >>> w.index("x").tolist()          # stages x components
    [[0, 1], [4, 5]]
    >>> w.index("u", 1).tolist()       # component 1 of u at every stage
    [3]
    """

    def __init__(self, name: str, sym_type=ca.SX):
        self.name = name
        self.sym_type = sym_type  # ca.SX, or ca.MX for an NLP that calls stage functions
        self._parts: list = []
        self._blocks: dict[str, dict[int, np.ndarray]] = {}
        self.size = 0

    def add(self, block: str, stage: int, expr) -> ca.SX:
        """Append ``expr`` (a CasADi column, symbol or expression) as ``block`` of ``stage``."""
        expr = ca.SX(expr) if not isinstance(expr, (ca.SX, ca.MX)) else expr
        n = int(expr.numel())
        stages = self._blocks.setdefault(block, {})
        if stage in stages:
            raise ValueError(f"{self.name}: block {block!r} of stage {stage} added twice")
        if stages and n != next(iter(stages.values())).size:
            raise ValueError(f"{self.name}: block {block!r} changes size at stage {stage}")
        stages[stage] = np.arange(self.size, self.size + n)
        self._parts.append(expr)
        self.size += n
        return expr

    def sym(self, block: str, stage: int, n: int) -> ca.SX:
        """Append a fresh symbol of ``n`` entries as ``block`` of ``stage`` and return it."""
        return self.add(block, stage, self.sym_type.sym(f"{block}_{stage}", n))

    def vertcat(self):
        """The whole vector, blocks in the order they were added."""
        return ca.vertcat(*self._parts)

    def stages(self, block: str) -> list[int]:
        """The stages at which ``block`` occurs, ascending."""
        return sorted(self._blocks[block])

    def index(self, block: str, component: int | None = None) -> np.ndarray:
        """Indices of ``block`` over its stages (ascending).

        Returns an (n_stages, n) array, or (n_stages,) for one ``component``.
        """
        if block not in self._blocks:
            raise KeyError(f"{self.name}: no block {block!r}")
        idx = np.stack([self._blocks[block][k] for k in self.stages(block)])
        return idx if component is None else idx[:, component]

    def at(self, block: str, stage: int) -> np.ndarray:
        """Indices of ``block`` at one ``stage``."""
        return self._blocks[block][stage]

    @property
    def blocks(self) -> tuple[str, ...]:
        """Block names in order of first appearance."""
        return tuple(self._blocks)
