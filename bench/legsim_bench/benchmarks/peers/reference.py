"""The reference trajectory the peers are checked against.

Prefers the bench's independent reference model (``legsim_bench.reference``:
minimal coordinates + DOP853); falls back to the peers' own absolute-
coordinate check (:mod:`.selfref`) when that package is not importable. The
two agree to ~4e-13 m at t = 0.1 s on both scenes and both variants (checked
in tests/bench/test_peers.py whenever both are present).
"""
from __future__ import annotations

import numpy as np

from . import leg_model as lm
from . import selfref


def bench_reference_available() -> bool:
    try:
        from legsim_bench.reference import ForceCommand, LegModel  # noqa: F401
    except ImportError:
        return False
    return True


def run_bench_reference(scene: str, t_end: float, *, variant: str = "revolute", t_eval=None,
                        model_path=None) -> dict:
    from legsim_bench.reference import ForceCommand, LegModel

    model = lm.load(model_path, variant)
    forces = lm.scene_forces(model, scene)
    ref = LegModel.from_toml(str(model_path or lm.DEFAULT_MODEL), variant=variant)
    t_eval = np.array([0.0, t_end]) if t_eval is None else np.asarray(t_eval, float)
    r = ref.simulate(t_end, t_eval=t_eval, actuators=[ForceCommand(F) for F in forces])
    return {"t": np.asarray(r.t), "q": np.asarray(r.q), "qd": np.asarray(r.qd),
            "engine": "legsim_bench.reference (minimal coordinates, DOP853)", "variant": variant}


def reference(scene: str, t_end: float, *, variant: str = "revolute", t_eval=None,
              model_path=None, prefer: str = "bench") -> dict:
    """dict(t, q, qd, engine): the bench reference if importable, else selfref."""
    if prefer == "bench" and bench_reference_available():
        return run_bench_reference(scene, t_end, variant=variant, t_eval=t_eval,
                                   model_path=model_path)
    return selfref.run(scene, t_end, variant=variant, t_eval=t_eval, model_path=model_path)
