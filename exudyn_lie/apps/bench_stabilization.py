"""``bench --sections stabilization``: what holding the joints costs in the drop-in.

``exl.SolveDynamic`` projects the configuration onto the joints after every step by default
(``stabilization='auto'`` = ``'position'``: Gauss-Newton on the group, then the
velocities), as Exudyn's generalized-alpha holds them to its Newton tolerance.  Per paper
model with joints: the medians of whole ``exl.SolveDynamic`` calls with the default and
with ``stabilization=None`` (the paper's unstabilised method), interleaved round by round,
at Exudyn's default output period of 0.01 s with a sensor, h = 1e-3 s, and the largest joint
violation at the end of each (position and rotation rows of the model's joints,
``models.geometry.joint_violations``).  With ``evaluation='exudyn'`` the same on the
Exudyn-evaluated path, which projects onto Exudyn's own constraints after every Exudyn step
(bridge/evaluated_projection.py)."""
from __future__ import annotations

import numpy as np

MODELS = ("heavy_top", "spherical_double_pendulum", "planar_four_bar", "cardan_shaft")


def _final_violation(mbs, info):
    import exudyn as exu
    from exudyn_lie.models.geometry import joint_violations
    O = exu.OutputVariableType
    R = np.array([np.array(mbs.GetNodeOutput(n, O.RotationMatrix)).reshape(3, 3) for n in info.nodes])[None]
    r = np.array([mbs.GetNodeOutput(n, O.Position) for n in info.nodes], float)[None]
    return max(float(max(t[0], q[0])) for t, q in (joint_violations(j, R, r) for j in info.joints))


def stabilization_cost(T=2.0, h=1e-3, period=0.01, repeats=7, models_=MODELS, evaluation="auto"):
    from .bench_micro import timed_paper_solve

    def one(name, stabilization):
        t, mbs, info = timed_paper_solve(name, T, h, period, stabilization=stabilization, evaluation=evaluation)
        return t, _final_violation(mbs, info)

    out = {}
    for name in models_:
        one(name, "auto"), one(name, None)                    # compile / warm up
        on, off = [], []
        for _ in range(repeats):
            on.append(one(name, "auto"))
            off.append(one(name, None))
        a, b = float(np.median([x[0] for x in on])), float(np.median([x[0] for x in off]))
        out[name] = dict(on=a, off=b, share=(a - b) / b, violationOn=on[-1][1], violationOff=off[-1][1], T=T)
    return out
