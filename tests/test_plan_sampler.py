"""The plan's one sampler against a slow, written-out reference at random times.

The reference below walks the step list one instant at a time in plain Python, from the
definitions in the docstring of controller/footsteps.py (it shares no code with the
sampler), so any shortcut the compiled sampler takes is checked.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.footsteps import LEFT, RIGHT, FootstepPlan, TickSamples, plan_footsteps
from controller.params import WalkParams
from models.dyros_jet import FOOT_SIZE


def reference(plan: FootstepPlan, t: float, margin: float) -> dict:
    """The plan at one instant, step by step (slow, obvious)."""
    t = min(max(t, 0.0), plan.t_end)
    n = len(plan.step_start)
    end_last = plan.step_start[-1] + plan.step_duration[-1]
    k = -1
    for j in range(n):
        if plan.step_start[j] <= t:
            k = j
    if t >= end_last:
        k = n
    feet = [list(plan.feet_init[LEFT]), list(plan.feet_init[RIGHT])]
    vel = [[0.0] * 3, [0.0] * 3]
    out = {"step": k, "standing": k < 0 or k >= n}
    if k < 0:
        mid = (plan.feet_init[:, :2].sum(axis=0) / 2).tolist()
        zmp, ground = mid, [feet[LEFT], feet[RIGHT]]
        out.update(in_dsp=False, in_ssp=False, swing_side=-1, s_ssp=0.0)
    elif k >= n:
        feet = [list(plan.feet_final[LEFT]), list(plan.feet_final[RIGHT])]
        last = plan.support_pos[-1, :2]
        if plan.step_dsp_end[-1] > 0:  # both_ends: the closing step ends mid-way to the feet
            last = last + 0.5 * (plan.swing_to[-1, :2] - last)
        mid = plan.feet_final[:, :2].sum(axis=0) / 2
        a = min(max((t - end_last) / max(plan.final_dsp_time, 1e-9), 0.0), 1.0)
        zmp, ground = (last + a * (mid - last)).tolist(), [feet[LEFT], feet[RIGHT]]
        out.update(in_dsp=False, in_ssp=False, swing_side=-1, s_ssp=1.0)
    else:
        tau = t - plan.step_start[k]
        dsp, dur, dsp_end = plan.step_dsp[k], plan.step_duration[k], plan.step_dsp_end[k]
        side = int(plan.swing_side[k])
        support = list(plan.support_pos[k])
        ssp = max(dur - dsp - dsp_end, 1e-9)
        in_ssp = dsp <= tau < dsp + ssp
        s = min(max((tau - dsp) / ssp, 0.0), 1.0)
        p0, p1, h = plan.swing_from[k], plan.swing_to[k], plan.step_height[k]
        if s <= 0.0:
            sw, vsw = list(p0), [0.0] * 3
        elif s >= 1.0:
            sw, vsw = list(p1), [0.0] * 3
        else:
            c = 3 * s**2 - 2 * s**3
            dc = (6 * s - 6 * s**2) / ssp
            sw = [p0[i] + (p1[i] - p0[i]) * c for i in range(3)]
            vsw = [(p1[i] - p0[i]) * dc for i in range(3)]
            sw[2] += h * (1 - math.cos(2 * math.pi * s)) / 2
            vsw[2] += h * math.pi * math.sin(2 * math.pi * s) / ssp
        feet[side], vel[side] = sw, vsw
        feet[1 - side], vel[1 - side] = support, [0.0] * 3
        a = min(max(tau / max(dsp, 1e-9), 0.0), 1.0)
        zf = plan.zmp_from[k, :2]
        zmp = [zf[i] + a * (support[i] - zf[i]) for i in range(2)]
        if dsp_end > 0:  # both_ends: after the touch-down on to the support-landed midpoint
            b = min(max((tau - dsp - ssp) / dsp_end, 0.0), 1.0)
            zmp = [zmp[i] + b * 0.5 * (p1[i] - support[i]) for i in range(2)]
        ground = [support] if in_ssp else [support, list(p1 if s >= 1.0 else p0)]
        out.update(in_dsp=not in_ssp, in_ssp=in_ssp, swing_side=side, s_ssp=s)
    hx, hy = max(FOOT_SIZE[0] / 2 - margin, 0), max(FOOT_SIZE[1] / 2 - margin, 0)
    out["zmp_lo"] = [min(g[0] for g in ground) - hx, min(g[1] for g in ground) - hy]
    out["zmp_hi"] = [max(g[0] for g in ground) + hx, max(g[1] for g in ground) + hy]
    out.update(
        zmp_ref=zmp, p_left=feet[LEFT], p_right=feet[RIGHT], v_left=vel[LEFT], v_right=vel[RIGHT]
    )
    return out


def _plans() -> list[FootstepPlan]:
    base = plan_footsteps(WalkParams(step_length=0.3, dsp_ratio=0.25, n_steps=5))
    other = WalkParams(step_length=0.15, step_time=0.9, dsp_ratio=0.1, foot_height=0.1, n_steps=7)
    return [
        base,
        plan_footsteps(
            WalkParams(step_length=0.42, step_time=1.4, n_steps=3), first_swing=RIGHT, x0=0.7
        ),
        base.replanned(other, base.step_start[2] + 0.3),  # per-step timings differ
        plan_footsteps(
            WalkParams(step_length=0.35, dsp_ratio=0.3, n_steps=4, dsp_split="both_ends")
        ),
        base.replanned(  # from our split to the authors' mid-walk
            WalkParams(step_length=0.2, dsp_ratio=0.2, n_steps=5, dsp_split="both_ends"),
            base.step_start[1] + 0.1,
        ),
    ]


@pytest.mark.parametrize("which", range(5))
def test_sampler_matches_the_reference_at_random_times(which):
    plan = _plans()[which]
    rng = np.random.default_rng(which)
    times = np.concatenate(
        [
            rng.uniform(-0.5, plan.t_end + 0.5, 400),
            plan.step_start,
            plan.liftoff_times(),
            plan.landing_times(),  # the phase boundaries
            [0.0, plan.t_end, plan.walk_end],
        ]
    )
    margin = 0.015
    got = plan.sample(times, margin)
    for i, t in enumerate(times):
        ref = reference(plan, float(t), margin)
        for key, want in ref.items():
            have = getattr(got, key)[i]
            if isinstance(want, bool):
                assert bool(have) == want, (key, t)
            elif isinstance(want, int):
                assert int(have) == want, (key, t)
            else:
                np.testing.assert_allclose(have, want, atol=1e-12, err_msg=f"{key} at t={t}")
    np.testing.assert_array_equal(
        got.support_side[got.swing_side >= 0], 1 - got.swing_side[got.swing_side >= 0]
    )


def test_a_scalar_time_gives_one_row():
    plan = _plans()[0]
    one = plan.sample(1.234, 0.02)
    many = plan.sample(np.array([1.234]), 0.02)
    for a, b in zip(one, many, strict=True):
        np.testing.assert_array_equal(a, b)
        assert len(a) == 1


@pytest.mark.parametrize("which", range(5))
def test_tick_table_holds_what_the_sampler_gives_at_the_ticks_times(which):
    """The plan's table of the coming ticks is the sampler's answer, bit for bit, at the
    times a walker queries: t (its clock, advanced by t += dt), t + dt and t + k T_p."""
    plan = _plans()[which]
    dt, margin = 0.005, 0.02
    offsets = 0.1 * np.arange(1, 17)
    t = 0.4 - 60 * dt  # a table may start anywhere
    n_ticks = int((plan.t_end + 0.3 - t) / dt)
    table = TickSamples(plan, margin, dt, offsets, t, n_ticks)
    for j in range(n_ticks):
        assert table.covers(plan, margin, offsets, t, j)
        times = np.concatenate(((t, t + dt), t + offsets))
        np.testing.assert_array_equal(table.times[j], times)
        want = plan.sample(times, margin)
        for name, have, expected in zip(want._fields, table.at(j), want, strict=True):
            np.testing.assert_array_equal(have, expected, err_msg=f"{name} at tick {j}")
        t = t + dt
    assert not table.covers(plan, margin, offsets, t, n_ticks)  # past its end
    assert not table.covers(plan, margin + 0.01, offsets, table.ticks[0], 0)
    assert not table.covers(
        _plans()[0] if which else _plans()[1], margin, offsets, table.ticks[0], 0
    )
