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

from synth.exceptions import SpecError
from synth.models.uncertainty import PARAMS, Uncertainty

SAMPLE_BUDGET = 100_000
"""Draws within the bounds after which :meth:`ParameterSpace.sample` judges its acceptance:
at the :data:`MIN_ACCEPTANCE` rate 10⁵ draws accept 10 on average, so a set that accepts
fewer than 10 of them is declared too thin to sample rather than drawn from for ever."""
MIN_ACCEPTANCE = 1e-4
"""Acceptance rate (feasible draws / draws) below which sampling gives up: the coupled
constraints leave an empty set, or one so thin (an equality, a sliver) that rejection sampling
would take 10⁴ draws per sample or more."""


class SamplingError(SpecError, ValueError):
    """The coupled constraints of the blocks ``path`` names reject (nearly) every draw.

    A :class:`~synth.exceptions.SpecError`, so the CLI exits 2 with its one-line message and
    the server answers 422, as for any other unusable task; a :class:`ValueError` for callers
    of :class:`ParameterSpace` outside the task layer. ``drawn`` and ``accepted`` are the
    draws made and kept when sampling gave up.
    """

    def __init__(self, path: str, message: str, drawn: int, accepted: int) -> None:
        super().__init__(path, message)
        self.drawn = drawn
        self.accepted = accepted

    def __reduce__(self) -> tuple[type[SamplingError], tuple[str, str, int, int]]:
        # Raised in a replay worker process, it must survive the trip back by pickle
        # (SpecError's own (path, message) constructor does not match its args).
        return type(self), (self.path, self.detail, self.drawn, self.accepted)


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

        Bounded: once :data:`SAMPLE_BUDGET` (10⁵) draws are made and fewer than
        :data:`MIN_ACCEPTANCE` (10⁻⁴) of them satisfy the coupled constraints, it raises
        :class:`SamplingError` naming the blocks and the rows that reject the draws, with the
        acceptance observed. The loader's LP (``synth.models.loader``) refuses an empty block,
        but an equality (``min == max``), a sliver, or rows added with :meth:`constrain` can
        still leave a set that rejection sampling would never hit. Draws are made in the same
        rounds as without the bound, so a feasible space gives the same samples as before.
        """
        out = np.empty((0, self.dim))
        drawn = 0
        while out.shape[0] < n:
            want = max(2 * (n - out.shape[0]), 64)
            parts = []
            for b in self.blocks:
                if b.distribution == "normal":
                    from scipy.stats import truncnorm  # slow to import; most tasks are uniform

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
            drawn += want
            short = out.shape[0] < n
            if short and drawn >= SAMPLE_BUDGET and out.shape[0] < MIN_ACCEPTANCE * drawn:
                raise self._too_thin(v, drawn, out.shape[0])
        return out[:n]

    def _too_thin(self, v: np.ndarray, drawn: int, accepted: int) -> SamplingError:
        """The error of :meth:`sample`: the rows rejecting most of the last draws ``v``."""
        a, b = self.constraint_matrix()
        rejects = (v @ a.T > b + 1e-12).mean(axis=0) if a.shape[0] else np.zeros(0)
        order = [int(i) for i in np.argsort(-rejects, kind="stable") if rejects[i] > 0][:3]
        labels = self.labels
        rows = []
        owners: list[str] = []
        for i in order:
            used = [k for k in range(self.dim) if a[i, k] != 0.0]
            rows.append(
                f"{_linear(a[i, used], [labels[k] for k in used])} ≤ {b[i] + 0.0:g} "
                f"(rejects {100 * rejects[i]:.0f}% of the last draws)"
            )
            for k in used:
                owner = labels[k].rsplit(".", 1)[0]
                if owner not in owners:
                    owners.append(owner)
        if not owners:  # no row rejected the last draws: name every constrained block
            owners = [blk.owner for blk in self.blocks if blk.a_ub.shape[0]] or [
                blk.owner for blk in self.blocks
            ]
        rate = accepted / drawn
        return SamplingError(
            "uncertainty of " + ", ".join(owners),
            f"{accepted} of {drawn} draws within the bounds satisfy the coupled constraints "
            f"(acceptance {rate:.1e}, below {MIN_ACCEPTANCE:.0e}): the set they leave is empty "
            "or too thin for the replay to sample"
            + (f"; rejecting most: {'; '.join(rows)} [m, rad]" if rows else ""),
            drawn,
            accepted,
        )

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


def _linear(coefficients: np.ndarray, names: list[str]) -> str:
    """``BOX.x − 2·BOX.rz``: a row of ``A`` as the sum it stands for."""
    out = ""
    for c, name in zip(coefficients, names, strict=True):
        sign = "−" if c < 0 else "+"
        term = name if abs(c) == 1.0 else f"{abs(c):g}·{name}"
        out += (f" {sign} " if out else ("−" if c < 0 else "")) + term
    return out
