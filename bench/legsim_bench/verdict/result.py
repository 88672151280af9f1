"""A verdict: the rows of the pass/fail table (CheckResult) and the arrays behind them
(Evaluation), whichever checks made them."""
from __future__ import annotations

from dataclasses import dataclass, field

from ..scene import Scene
from .leg import Leg

__all__ = ["CheckResult", "Evaluation"]


@dataclass
class CheckResult:
    name: str
    passed: bool
    error: float | None = None        # worst error (or the measured value)
    tolerance: float | None = None
    unit: str = ""
    where: str = ""
    detail: str = ""
    got: str | None = None            # non-numeric outcome (e.g. the fault code received)
    want: str | None = None           # and what was expected

    @property
    def verdict(self) -> str:
        return "PASS" if self.passed else "FAIL"

    def as_dict(self) -> dict:
        return {"check": self.name, "result": self.verdict, "error": self.error,
                "tolerance": self.tolerance, "unit": self.unit, "where": self.where,
                "detail": self.detail, "got": self.got, "expected": self.want}


@dataclass
class Evaluation:
    scene: Scene
    rec: dict
    results: list[CheckResult]
    data: dict = field(default_factory=dict)     # arrays: t, q, ... (received)
    ref: dict | None = None                      # arrays of the reference at the same times
    leg: Leg | None = None
    reference_run: object | None = None          # robot: the reference's run (the report's curves)

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results) and bool(self.results)

    @property
    def n_failed(self) -> int:
        return sum(not r.passed for r in self.results)
