"""Independent reference model of the leg (minimal coordinates + Newton-Euler).

Quick use::

    from legsim_bench.reference import LegModel, ForceCommand, LengthCommand, Sinusoid
    m = LegModel.from_toml("models/leg.toml")            # or variant="slot"
    th = m.stand_theta(); q = m.absolute_q(th)
    F, R = m.statics(m.lengths(th), foot_load=(0.0, 300.0))
    res = m.simulate(0.1, t_eval=[0.0, 0.1], actuators=[ForceCommand(0.0), ForceCommand(0.0)])

See model.py for the formulation and README.md for the API summary.
"""
from .commands import ForceCommand, Hold, LengthCommand, Sinusoid, Staircase, Step
from .model import (InverseDynamics, LegModel, NoEquilibriumError, ReferenceError, Result,
                    UnreachableError, WorstCase, n, u)

__all__ = ["LegModel", "Result", "InverseDynamics", "WorstCase", "ForceCommand", "LengthCommand",
           "Hold", "Step", "Sinusoid", "Staircase", "ReferenceError", "UnreachableError",
           "NoEquilibriumError", "u", "n"]
