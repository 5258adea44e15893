"""The free variables of an error estimate: bounded parameter blocks and their constraints.

Seed Eqn 3.5.1 (L2205): errors are linear in free variables v subject to ``c_j(v) ≤ b_j``. Each
uncertain link contributes one block (its bounded x, y, z, rx, ry, rz); blocks are stacked into
one vector ``v`` with bounds ``lo ≤ v ≤ hi`` and coupled constraints ``A v ≤ b``. The planner
adds constraints across blocks (a tap measurement, seed §4.5.2) with
:meth:`ParameterSpace.constrain`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import truncnorm

from synth.models.spec import PARAMS, Uncertainty


@dataclass(frozen=True, eq=False)
class ParameterBlock:
    """The bounded error parameters of one link, in canonical order (x, y, z, rx, ry, rz)."""

    owner: str
    names: tuple[str, ...]
    lo: np.ndarray
    hi: np.ndarray
    a_ub: np.ndarray
    b_ub: np.ndarray
    distribution: str = "uniform"

    @classmethod
    def from_uncertainty(cls, owner: str, unc: Uncertainty) -> ParameterBlock:
        """Block for a spec uncertainty; ``min ≤ c·v ≤ max`` becomes rows of ``A v ≤ b``."""
        bounds = unc.bounds()
        names = tuple(bounds)
        rows, rhs = unc.constraint_rows()
        return cls(
            owner=owner,
            names=names,
            lo=np.array([b.lo for b in bounds.values()], dtype=float),
            hi=np.array([b.hi for b in bounds.values()], dtype=float),
            a_ub=np.array(rows, dtype=float).reshape(len(rows), len(names)),
            b_ub=np.array(rhs, dtype=float),
            distribution=unc.distribution,
        )

    @property
    def size(self) -> int:
        """Number of parameters in the block."""
        return len(self.names)

    def index(self, param: str) -> int | None:
        """Position of ``param`` (one of x, y, z, rx, ry, rz) in the block, if bounded."""
        assert param in PARAMS
        return self.names.index(param) if param in self.names else None


@dataclass(frozen=True, eq=False)
class ParameterSpace:
    """All blocks of one estimate stacked into ``v``; the feasible set is a polytope."""

    blocks: tuple[ParameterBlock, ...]
    extra_a: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    extra_b: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def offsets(self) -> tuple[int, ...]:
        """Start index of each block in ``v``."""
        if not self.blocks:
            return ()
        return tuple(itertools.accumulate((b.size for b in self.blocks[:-1]), initial=0))

    @property
    def dim(self) -> int:
        """Length of ``v``."""
        return sum(b.size for b in self.blocks)

    @property
    def labels(self) -> tuple[str, ...]:
        """``owner.param`` for each entry of ``v``."""
        return tuple(f"{b.owner}.{n}" for b in self.blocks for n in b.names)

    @property
    def lo(self) -> np.ndarray:
        """Lower bounds of ``v``."""
        return np.concatenate([b.lo for b in self.blocks]) if self.blocks else np.zeros(0)

    @property
    def hi(self) -> np.ndarray:
        """Upper bounds of ``v``."""
        return np.concatenate([b.hi for b in self.blocks]) if self.blocks else np.zeros(0)

    @property
    def magnitude(self) -> np.ndarray:
        """``max(|lo_i|, |hi_i|)``: the box hull radius of each parameter about 0."""
        return np.maximum(np.abs(self.lo), np.abs(self.hi))

    def constraint_matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """All coupled constraints ``A v ≤ b`` (block rows, then extra rows)."""
        n = self.dim
        rows = []
        rhs = []
        for off, b in zip(self.offsets, self.blocks, strict=True):
            if b.a_ub.shape[0]:
                a = np.zeros((b.a_ub.shape[0], n))
                a[:, off : off + b.size] = b.a_ub
                rows.append(a)
                rhs.append(b.b_ub)
        if self.extra_a.shape[0]:
            rows.append(self.extra_a)
            rhs.append(self.extra_b)
        if not rows:
            return np.zeros((0, n)), np.zeros(0)
        return np.vstack(rows), np.concatenate(rhs)

    @property
    def is_box(self) -> bool:
        """True when the feasible set is just the bounds (closed-form extrema apply)."""
        return self.constraint_matrix()[0].shape[0] == 0

    def constrain(self, a: np.ndarray, b: np.ndarray) -> ParameterSpace:
        """A new space with extra rows ``a v ≤ b`` (e.g. what a tap measured)."""
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_1d(np.asarray(b, dtype=float))
        if self.extra_a.shape[0]:
            a = np.vstack([self.extra_a, a])
            b = np.concatenate([self.extra_b, b])
        return ParameterSpace(self.blocks, a.copy(), b.copy())

    def block_slice(self, owner: str) -> slice:
        """Slice of ``v`` belonging to the block of ``owner``."""
        for off, b in zip(self.offsets, self.blocks, strict=True):
            if b.owner == owner:
                return slice(off, off + b.size)
        raise KeyError(owner)

    def feasible(self, v: np.ndarray, tol: float = 1e-12) -> np.ndarray:
        """Mask of the rows of ``v`` (shape (N, dim)) that satisfy bounds and constraints."""
        v = np.atleast_2d(v)
        ok = np.all((v >= self.lo - tol) & (v <= self.hi + tol), axis=1)
        a, b = self.constraint_matrix()
        if a.shape[0]:
            ok &= np.all(v @ a.T <= b + tol, axis=1)
        return ok

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` feasible samples: each block by its distribution, rejecting infeasible ones.

        Normal blocks use σ = tolerance/3 truncated at the bounds (seed L7242), the tolerance
        being the larger half-width of each parameter.
        """
        out = np.empty((0, self.dim))
        while out.shape[0] < n:
            want = max(2 * (n - out.shape[0]), 64)
            parts = []
            for b in self.blocks:
                if b.distribution == "normal":
                    sigma = np.maximum(np.maximum(np.abs(b.lo), np.abs(b.hi)) / 3.0, 1e-300)
                    parts.append(
                        truncnorm.rvs(
                            b.lo / sigma,
                            b.hi / sigma,
                            scale=sigma,
                            size=(want, b.size),
                            random_state=rng,
                        )
                    )
                else:
                    parts.append(rng.uniform(b.lo, b.hi, size=(want, b.size)))
            v = np.hstack(parts) if parts else np.zeros((want, 0))
            out = np.vstack([out, v[self.feasible(v)]])
        return out[:n]

    def corners(self) -> np.ndarray:
        """Every vertex of the bounding box that satisfies the coupled constraints.

        There are 2^dim of them; above 20 parameters (a million vertices) this refuses rather
        than exhaust memory.
        """
        if self.dim > 20:
            raise ValueError(f"{self.dim} parameters have 2^{self.dim} vertices; sample them")
        lo, hi = self.lo, self.hi
        grid = np.array(list(itertools.product((0, 1), repeat=self.dim)), dtype=float)
        v = lo + grid * (hi - lo)
        return v[self.feasible(v)]
