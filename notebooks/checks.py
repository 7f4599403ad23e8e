"""Checks for the course's exercises: run one after your answer.

Each check prints one line: ✓ (right), ✗ (not yet, with a hint) or … (not answered: the answer
is still ``...``); its value's ``ok`` is True, False or None (the notebook shows nothing more).
A check never stops the notebook, so the lesson runs top to bottom before you have answered
anything. The right answers are computed here
from the tool itself (``pelvic_walk``) or from the runs you pass in, never typed in.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import pelvic_walk as pw

OK, NOT_YET, OPEN = "\u2713", "\u2717", "\u2026"
PAPER_METHODS = ("fixed", "redundancy", "mpc")  # not a student's strategy


class Verdict:
    """A check's outcome: ``ok`` is True, False or None (not answered). A notebook shows
    nothing for it: the check has printed its line."""

    def __init__(self, ok: bool | None):
        self.ok = ok

    def __bool__(self) -> bool:
        return bool(self.ok)

    def __repr__(self) -> str:
        return f"Verdict({self.ok})"

    def _ipython_display_(self) -> None:
        pass


def _unanswered(answer: Any, what: str) -> bool:
    if answer is ...:
        print(f"{OPEN} not answered yet: {what}")
        return True
    return False


def _number(answer: Any, right: float, tol: float, what: str, hint: str) -> bool | None:
    if _unanswered(answer, what):
        return None
    try:
        value = float(answer)
    except (TypeError, ValueError):
        print(f"{NOT_YET} {what}: expected a number, got {answer!r}")
        return False
    if math.isfinite(value) and abs(value - right) <= tol:
        print(f"{OK} right: {value:.4g}")
        return True
    print(f"{NOT_YET} not yet ({value:.4g}). Hint: {hint}")
    return False


def _choice(answer: Any, right: str, choices: tuple[str, ...], what: str, why: str) -> bool | None:
    if _unanswered(answer, what):
        return None
    if answer not in choices:
        print(f"{NOT_YET} answer one of {', '.join(map(repr, choices))}, got {answer!r}")
        return False
    if answer == right:
        print(f"{OK} right: {why}")
        return True
    print(f"{NOT_YET} not {answer!r}: look at the numbers again ({why.split(':')[0]}).")
    return False


def _verdict(check: Any) -> Any:
    """A check returning True / False / None -> one returning a :class:`Verdict`."""

    def run(*args: Any, **kwargs: Any) -> Verdict:
        return Verdict(check(*args, **kwargs))

    run.__name__, run.__doc__ = check.__name__, check.__doc__
    return run


# -- 1 why turning the pelvis lengthens the step ---------------------------------------------
@_verdict
def eq4(answer: Any) -> bool | None:
    """Eq. (4) with the paper's numbers [m]."""
    right = pw.analyze()["step_max_fixed_static"]
    return _number(
        answer,
        right,
        5e-4,
        "the static step of a fixed pelvis, eq. (4), in metres",
        "the stretched leg l_leg is the hypotenuse, the hip height z0 one side",
    )


@_verdict
def best_angle(answer: Any) -> bool | None:
    """The pelvic angle [deg] at which l_pel sin(theta) cos(theta) is largest."""
    return _number(
        answer,
        45.0,
        0.5,
        "the angle [deg] of the largest gain",
        "sin(theta) cos(theta) = sin(2 theta) / 2",
    )


@_verdict
def our_increase(answer: Any) -> bool | None:
    """Eq. (5) over eq. (4) for our robot at 45 deg [%]."""
    right = pw.analyze(**pw.robot())["increase_percent"]
    return _number(
        answer,
        right,
        0.05,
        "eq. (5) over eq. (4) for our robot, in percent",
        "pw.analyze(**pw.robot()) takes our robot's numbers",
    )


@_verdict
def static_gain_at(answer: Any, run: pw.Run) -> bool | None:
    """Eq. (5)'s static step [m] at the waist angle ``run`` reached."""
    theta = run.summary["waist_yaw_max_deg"]
    right = pw.analyze(**pw.robot(), theta_pel_deg=theta)["step_max_rotation_static"]
    return _number(
        answer,
        right,
        5e-4,
        "eq. (5)'s step at the MPC's largest waist angle, in metres",
        "theta_pel_deg=run.summary['waist_yaw_max_deg'] with pw.robot()'s numbers",
    )


# -- 2 the CoM MPC and its prediction --------------------------------------------------------
@_verdict
def horizon_samples(answer: Any, run: pw.Run) -> bool | None:
    p = run.params.com
    return _number(
        answer,
        round(p.horizon / p.sample_time),
        1e-6,
        "N, the samples of the horizon",
        "N = H / T_p: run.params.com.horizon / run.params.com.sample_time, and the table's rows",
    )


@_verdict
def zmp_inside(answer: Any, plan: Any) -> bool | None:
    """Whether every predicted ZMP sample of ``plan`` (a ``run.horizon(t)`` table) is inside
    its bounds."""
    zx, zy = plan["zmp_x [m]"], plan["zmp_y [m]"]
    inside = bool(
        ((zx >= plan["zmp_min_x [m]"] - 1e-6) & (zx <= plan["zmp_max_x [m]"] + 1e-6)).all()
        and ((zy >= plan["zmp_min_y [m]"] - 1e-6) & (zy <= plan["zmp_max_y [m]"] + 1e-6)).all()
    )
    if _unanswered(answer, "True or False"):
        return None
    if not isinstance(answer, (bool, np.bool_)):
        print(f"{NOT_YET} answer True or False, got {answer!r}")
        return False
    if bool(answer) == inside:
        print(f"{OK} right: the bounds of eq. (18) are constraints of the QP, so they hold")
        return True
    print(f"{NOT_YET} not yet. Hint: compare zmp_x with zmp_min_x and zmp_max_x, y alike")
    return False


@_verdict
def prediction_error(answer: Any, run: pw.Run, plan: Any, ahead: float) -> bool | None:
    """|predicted - measured| CoM y [cm] ``ahead`` seconds after the plan's instant."""
    rows = plan[np.isclose(plan["ahead [s]"], ahead)]
    if rows.empty:
        print(f"{NOT_YET} the plan has no sample {ahead} s ahead")
        return False
    t = float(rows["t [s]"].iloc[0])
    measured = float(np.interp(t, run.column("t"), run.column("com_y")))
    right = abs(float(rows["com_y [m]"].iloc[0]) - measured) * 100
    if not _unanswered(answer, "the prediction's error, in centimetres"):
        try:
            value = float(answer)
        except (TypeError, ValueError):
            value = math.nan
        if abs(abs(value) - right) <= 0.05 and value < 0:
            print(f"{NOT_YET} the size of the error is asked: take the absolute value (abs)")
            return False
        if abs(abs(value) * 100 - right) <= 0.05:
            print(f"{NOT_YET} that is in metres: the question asks for centimetres (x 100)")
            return False
    return _number(
        answer,
        right,
        0.05,
        "the prediction's error, in centimetres",
        "interpolate the measured com_y at the sample's time t (np.interp), subtract it from "
        "the predicted com_y, take the absolute value and give it in centimetres",
    )


@_verdict
def shortest_walking_horizon(answer: Any, runs: dict[float, pw.Run]) -> bool | None:
    """The shortest horizon H [s] of ``runs`` (H -> run) whose walk succeeded."""
    walked = [h for h, r in runs.items() if r.summary["success"]]
    if not walked:
        print(f"{NOT_YET} none of these walks succeeded: try longer horizons")
        return False
    return _number(
        answer,
        min(walked),
        1e-9,
        "the shortest horizon H [s] that walks",
        "the success column of the table; the horizon is the com.horizon column",
    )


# -- 3 the pelvic reference and MPC ----------------------------------------------------------
@_verdict
def more_turn(answer: Any, low: pw.Run, high: pw.Run) -> bool | None:
    right = (
        "high" if high.summary["waist_yaw_max_deg"] > low.summary["waist_yaw_max_deg"] else "low"
    )
    return _choice(
        answer,
        right,
        ("low", "high"),
        "'low' or 'high'",
        "k_pel: the share of the step made by turning the pelvis (eq. 31-32)",
    )


@_verdict
def tracking_error(answer: Any, run: pw.Run) -> bool | None:
    """RMS of (commanded waist angle - theta_ref) while walking [deg]."""
    walking = run.column("step_index") >= 0
    d = (run.column("waist_angle_cmd") - run.column("theta_ref"))[walking]
    right = math.degrees(float(np.sqrt(np.nanmean(d**2))))
    return _number(
        answer,
        right,
        0.01,
        "the RMS tracking error while walking, in degrees",
        "walking = step_index >= 0; the difference of waist_angle_cmd and theta_ref, squared,"
        " averaged (np.nanmean), square root, then np.degrees",
    )


@_verdict
def angle_at_touchdown(answer: Any, run: pw.Run) -> bool | None:
    """|waist angle| [deg] at the first touch-down (the last tick of the first step's single
    support)."""
    ssp = np.flatnonzero((run.column("step_index") == 0) & (run.column("in_ssp") == 1))
    if not len(ssp):
        print(f"{NOT_YET} this walk has no single support in its first step")
        return False
    right = abs(math.degrees(run.column("waist_angle")[ssp[-1]]))
    return _number(
        answer,
        right,
        0.05,
        "|waist angle| at the first touch-down, in degrees",
        "the last row with step_index 0 and in_ssp 1",
    )


# -- 4 the three methods compared ------------------------------------------------------------
@_verdict
def method_with(answer: Any, runs: list[pw.Run], key: str, largest: bool = True) -> bool | None:
    values = {r.method: r.summary[key] for r in runs}
    pick = max if largest else min
    right = pick(values, key=lambda m: values[m] if values[m] is not None else -math.inf)
    return _choice(
        answer,
        right,
        tuple(values),
        f"the method with the {'largest' if largest else 'smallest'} {key}",
        f"{key}: " + ", ".join(f"{m} {v:.3g}" for m, v in values.items()),
    )


@_verdict
def clean_at_long_step(answer: Any, runs: list[pw.Run]) -> bool | None:
    """The set of methods whose walk was clean."""
    right = {r.method for r in runs if r.summary["clean"]}
    if _unanswered(answer, "a set of method names, e.g. {'fixed'}"):
        return None
    given = set(answer) if isinstance(answer, (set, list, tuple)) else {answer}
    if given == right:
        print(f"{OK} right: clean at this length: {', '.join(sorted(right)) or 'none'}")
        return True
    print(f"{NOT_YET} not yet. Hint: the 'clean' column of pw.compare(runs)")
    return False


@_verdict
def arms_share(answer: Any, with_arms: pw.Run, without: pw.Run) -> bool | None:
    """How much of the yaw momentum peak the arm swing removes [%]."""
    a, b = with_arms.summary["yaw_momentum_peak"], without.summary["yaw_momentum_peak"]
    right = 100.0 * (1.0 - a / b)
    return _number(
        answer,
        right,
        0.5,
        "the share of the peak the arms remove, in percent",
        "100 * (1 - peak with arms / peak without)",
    )


def _constraint(name: str) -> str:
    """A constraint's name without its side and value: "left knee at its straight limit
    (0 deg)" -> "knee at its straight limit"."""
    name = name.strip().lower().split(" (")[0].strip()
    for side in ("left ", "right "):
        if name.startswith(side):
            name = name[len(side) :]
    return name


@_verdict
def stops_the_fixed_pelvis(answer: Any, run: pw.Run) -> bool | None:
    """The IK constraint that binds most often in ``run`` (the waist's pin aside), by name."""
    if _unanswered(answer, 'one constraint\'s name, e.g. "hip roll at its upper limit"'):
        return None
    if not isinstance(answer, str):
        print(
            f"{NOT_YET} answer one constraint's name as a string (you passed a "
            f"{type(answer).__name__}): read it in run.qp(t)['ik'].active"
        )
        return False
    s = run.series
    seen: dict[str, int] = {}
    for t in s.loc[s["active_ik"] > 1, "t [s]"]:  # more than the waist's pin
        for c in run.qp(float(t))["ik"].active:
            if c.kind != "pinned":
                seen[_constraint(c.name)] = seen.get(_constraint(c.name), 0) + 1
    if not seen:
        print(f"{NOT_YET} nothing but the waist's pin binds in this run: pass the 0.42 m walk")
        return False
    right = max(seen, key=lambda k: seen[k])
    given = _constraint(answer)
    if given == right:
        print(f"{OK} right: the {right} (at {seen[right]} of the ticks where the IK is stopped)")
        return True
    if given.startswith("waist rate pinned"):
        print(f"{NOT_YET} the pin is the fixed strategy's own rule, active every tick: what else?")
    elif given in seen:
        print(f"{NOT_YET} {given!r} binds too, but less often: which one binds most?")
    else:
        print(f"{NOT_YET} not yet. Hint: the names in run.qp(t)['ik'].active where active_ik > 1")
    return False


# -- 5 your own pelvis -----------------------------------------------------------------------
@_verdict
def clean_beside_mpc(mine: pw.Run, mpc: pw.Run) -> bool:
    """Your strategy walks cleanly where the MPC does (the same length and steps)."""
    s, m = mine.summary, mpc.summary
    if mine.method in PAPER_METHODS or mine.method == mpc.method:
        print(
            f"{NOT_YET} that is the {mine.method!r} run, not your strategy's: pass your own "
            "walk first, e.g. checks.clean_beside_mpc(mine, mpc) with "
            "mine = pw.simulate(strategy=Mine, ...)"
        )
        return False
    if mpc.method != "mpc":
        print(f"{NOT_YET} the second run must be the MPC's: pw.simulate('mpc', ...)")
        return False
    if (s["step_length"], s["steps_planned"]) != (m["step_length"], m["steps_planned"]):
        print(f"{NOT_YET} compare walks of the same length and steps")
        return False
    turn = (
        f"your waist turns {s['waist_yaw_max_deg']:.1f} deg, the MPC's "
        f"{m['waist_yaw_max_deg']:.1f} deg"
    )
    if not s["clean"]:
        if s["strategy_error"]:
            why = f"your strategy stopped: {s['strategy_error']}"
        elif s["fell"]:
            why = f"it fell ({s['fall_reason']})"
        elif s["condition_number_legs_max"] >= 1000:
            why = "a knee straightened (kappa of the legs above 1000): turn more, or earlier"
        else:
            why = "a landing off by 2 cm or more, a QP failure or a joint at its limit"
        print(f"{NOT_YET} not clean yet at {s['step_length']} m: {why}; {turn}")
        return False
    print(f"{OK} clean at {s['step_length']} m beside the MPC; {turn}")
    return True


@_verdict
def stopped_at(answer: Any, run: pw.Run) -> bool | None:
    """The time [s] the faulty strategy's walk stopped."""
    right = run.summary["strategy_error_time"]
    if right is None:
        print(f"{NOT_YET} this walk did not stop: its strategy raised nothing")
        return False
    return _number(
        answer,
        right,
        0.006,
        "when the walk stopped, in seconds",
        "run.summary['strategy_error_time'], or the last t of run.series",
    )


@_verdict
def smallest_clean_gain(answer: Any, table: Any, column: str) -> bool | None:
    """The smallest value of ``column`` in a sweep's ``table`` (``pw.sweep(...,
    measure="summary")``) whose walk is clean."""
    if column not in getattr(table, "columns", ()):
        print(f"{NOT_YET} the table has no column {column!r}: pass the sweep's table and its name")
        return False
    clean = [float(v) for v, ok in zip(table[column], table["clean"], strict=True) if ok]
    if not clean:
        print(f"{NOT_YET} no walk of this sweep is clean: sweep larger values")
        return False
    return _number(
        answer,
        min(clean),
        1e-9,
        f"the smallest {column} whose walk is clean",
        "the clean column of the table, read against the gain's column",
    )
