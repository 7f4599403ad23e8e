"""The Learn tab's content: guided lessons that walk through the paper, the presets of its
scenarios, short explanations per layer, and the checks of settings known to break walking.

Text and data only; :mod:`app.web.learn_gui` and :mod:`app.web.panel` build the controls, and
the equations and Fig. 1-2 are drawn in :mod:`app.web.lesson_math`. Every length promised
here was measured on this model with ``pelvic-walk simulate`` (see the comments).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from app.live import FALL_HOLD_S
from app.web import lesson_numbers
from app.web.lesson_math import analysis_html, analysis_numbers, analysis_svg, equations
from app.web.overlays import COLOUR_NAMES, DANGER, PREDICTED, REFERENCE
from controller import strategy
from controller.strategy import BUILTINS, FIXED, MPC, REDUNDANCY
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.robots import Robot

__all__ = [
    "CLEAN_LIMIT_M",
    "EXPLAIN",
    "LESSONS",
    "PRESETS",
    "Lesson",
    "analysis_html",
    "analysis_svg",
    "warnings_for",
]

# Longest steps walked cleanly on this model and the paper's (the reference report's "Longest
# step", `pelvic-walk experiments`: 10 steps of 1.2 s, the defaults), read from the report
# (app.web.lesson_numbers): the single source of "our limits" for the lessons, the analysis view
# and the warnings. Beyond them a method does not walk cleanly at the default timing.
CLEAN_LIMIT_M = lesson_numbers.clean_limits()
PAPER_LIMIT_M = lesson_numbers.paper_limits()
_P = lesson_numbers.paper()
# the words for the colours drawn (app.web.overlays): what a lesson names is what is drawn
_DANGER, _PREDICTED, _REFERENCE = (COLOUR_NAMES[c] for c in (DANGER, PREDICTED, REFERENCE))
_EQ5 = _P["kinematics"]["step_max_rotation"]  # [m] eq. (5) as the paper evaluates it

# The paper's scenarios, in one place: parameter groups to change (others keep their value)
# and optionally the methods to compare. Measured with `pelvic-walk simulate --method M
# --step-length L` (10 steps of 1.2 s, arms on):
#   0.30 m: every method clean.
#   0.40 m: fixed completes 10/10 steps but not cleanly: its swing knee straightens
#           (kappa of the legs ~1e9, reach 0.99+) and 33 IK ticks sit at the joint-speed
#           limit; mpc clean (kappa 47, waist 25 deg).
#   0.42 m: fixed falls in its second step (3.13 s, torso tilted over 30 deg); mpc clean.
PRESETS: dict[str, dict[str, Any]] = {  # button label (short: it must read whole) -> preset
    f"{PAPER_LIMIT_M['fixed']:.2f} m: every robot clean": {
        "walk": {"step_length": PAPER_LIMIT_M[FIXED], "step_time": 1.2},
        "methods": [FIXED, REDUNDANCY, MPC],
        "hint": "The paper's limit for the fixed pelvis: every robot walks cleanly here.",
    },
    f"{PAPER_LIMIT_M['mpc']:.2f} m: the fixed knee straightens": {
        "walk": {"step_length": PAPER_LIMIT_M[MPC], "step_time": 1.2},
        "methods": [FIXED, MPC],
        "hint": "The paper's limit with pelvic rotation: our fixed pelvis's swing knee "
        "straightens, the MPC stays clean.",
    },
    f"{_EQ5:.2f} m (eq. 5): the fixed pelvis falls": {
        "walk": {"step_length": _EQ5, "step_time": 1.2},
        "methods": [FIXED, MPC],
        "hint": "Eq. 5's step with the pelvis at 45 deg: our fixed pelvis falls, the MPC walks.",
    },
    "Defaults": {
        "walk": {"step_length": 0.2, "step_time": 1.2},
        "reset_groups": True,
        "hint": "Every parameter back to its default, 0.20 m steps.",
    },
}


@dataclass(frozen=True)
class Lesson:
    """One guided experiment: a button sets it up, the text says what to look for, and the
    live numbers (``numbers``: columns of :data:`app.web.learn_gui.COLUMNS`) show it."""

    title: str
    paper: str  # the equations and figures it is about
    walk: dict[str, Any]  # WalkParams fields set (the other groups back to their defaults)
    methods: tuple[str, ...]
    view: str  # a camera view of app.web.camera.CAMERA_VIEWS
    watch: str  # what to look for (HTML, two or three sentences)
    equations: tuple[str, ...]  # numbers of app.web.lesson_math.EQUATIONS
    numbers: tuple[str, ...]
    groups: dict[str, dict[str, Any]] = field(default_factory=dict)  # other parameter groups
    # one sentence read from the parameters in force (e.g. whether the arms swing now), shown
    # above ``watch``: the text follows what the student changed
    now: Callable[[Any], str] | None = None
    own: bool = False  # the server's own strategies (serve --strategy) walk beside ``methods``
    # robots with settings of their own (``NAME[,KEY=VALUE...][@LABEL]``, as ``serve --robot``):
    # when given, the lesson shows these instead of one robot per method (two robots of one
    # strategy side by side, each with its settings)
    robot_forms: tuple[str, ...] = ()

    def robot_list(self) -> tuple[Robot, ...]:
        """The robots the lesson shows: its ``robot_forms``, or one per method and, with
        ``own``, one per strategy the server loaded, in the registry's order."""
        if self.robot_forms:
            return tuple(robots_.parse(f) for f in self.robot_forms)
        users = tuple(n for n in strategy.names() if not strategy.info(n).builtin)
        methods = strategy.ordered(self.methods + users) if self.own else self.methods
        return robots_.of_methods(methods)

    def robots(self) -> tuple[str, ...]:
        """The keys (labels) of the robots the lesson shows (:meth:`robot_list`)."""
        return tuple(r.key for r in self.robot_list())

    def setup(self) -> dict[str, Any]:
        """The preset form (as :data:`PRESETS`): parameter groups from defaults, ``methods``
        (each robot's strategy) and ``robots`` (:meth:`robot_list`, with their settings)."""
        shown = self.robot_list()
        return {
            "walk": self.walk,
            **self.groups,
            "methods": [r.strategy for r in shown],
            "robots": list(shown),
            "reset_groups": True,
        }

    def equations_html(self) -> str:
        return equations(*self.equations)


# Two robots of the MPC side by side, measured with `pelvic-walk simulate --method mpc
# --step-length 0.4` (10 steps of 1.2 s):
#   k_pel 0.25 (default): success 10/10, waist max 25.1 deg, kappa max 44.4;
#   k_pel 0.45: success 10/10, waist max 39.7 deg, kappa max 33.4;
#   --horizon 1.2: fell at 2.56 s; --horizon 1.0: fell at 1.57 s; --horizon 0.8: fell at 1.40 s;
#   k_pel 0.45 with --horizon 1.2: fell at 2.55 s; with --horizon 0.8: fell at 1.39 s.
_K: dict[str, Any] = {
    "waist": (39.7, 25.1),
    "kappa": (33.4, 44.4),
    "falls": ((1.2, 2.55), (0.8, 1.39)),  # k_pel 0.45
}
# Lesson 9's two, as the live table reads them (the last two steps, once walking), measured
# with `pelvic-walk simulate --method mpc --step-length 0.4 --steps 20 --set pelvis.beta=B
# --csv x.csv`, the waist angle and kappa_legs over steps 4-15 (the summary's "waist max",
# 25.1 and 26.3 deg, is the first step's start-up):
#   B = 1e-6 (default): waist -24.5 to +24.5 deg, kappa max 46.3;
#   B = 0.01: waist -22.3 to +22.3 deg, kappa max 59.7. The live table shows the same.
_B = {"waist": (24.5, 22.3), "kappa": (46, 60)}

_F, _M = CLEAN_LIMIT_M[FIXED], CLEAN_LIMIT_M[MPC]
_PF, _PM = PAPER_LIMIT_M[FIXED], PAPER_LIMIT_M[MPC]
_EQ4 = analysis_numbers(_P["robot"]["theta_pel_deg"])  # eq. (4), (5) with the paper's inputs

LESSONS: tuple[Lesson, ...] = (
    Lesson(
        "1. Why the fixed pelvis cannot reach",
        "eq. 4-5, 45; Fig. 1-2, 13",
        {"step_length": _PM, "step_time": 1.2},
        (FIXED, MPC),
        "follow",
        f"At {_PM:.2f} m, the paper's limit with rotation, watch the fixed robot's <b>swing leg "
        f"turn {_DANGER}</b> (orange-red) at each landing: its reach (hip-to-ankle / leg "
        "length) nears 1, the knee "
        "is straight and <b>kappa(J)</b> of its legs explodes; its badge says <i>knee nearly "
        "straight</i> or <i>IK at the speed limit</i>. The MPC robot turns its pelvis (about "
        f"{lesson_numbers.mpc_waist_deg(_PM):.0f}°): its kappa at landing stays near "
        f"{lesson_numbers.kappa_legs_at_landing('mpc', _PM):.0f} and its badge <i>clean</i>. "
        f"Our limits: fixed {_F:.2f} m, MPC {_M:.2f} m (paper: {_PF:.2f} / {_PM:.2f} m); "
        f"press the preset <i>{_EQ5:.2f} m (eq. 5)</i> and the fixed robot falls. The row "
        "<i>what stops the IK</i> names the constraint that gives way, for a few ticks at each "
        "landing (its count grows walk by walk; pause at a landing to read it now): the fixed "
        "robot's knee at its <b>straight limit</b> (0°) while its waist rate stays pinned at "
        "0; the Inspect tab's QP view shows it with its multiplier, the four layers side by "
        "side.",
        ("4", "5", "45"),
        ("status", "shares", "active", "reach", "kappa_legs", "waist", "falls"),
    ),
    Lesson(
        "2. What the prediction does",
        "eq. 25-33, 34-38; Fig. 5-7",
        {"step_length": 0.40, "step_time": 1.2},
        (MPC,),
        "top",
        "Press <b>Pause</b>, then <b>Step: to landing</b> (Playback): it stops the instant "
        "a foot lands, with both feet down (phase <i>DSP</i> in the table above), which lasts "
        "only 0.24 s. Open the <b>Inspect</b> tab: the reference angle "
        "(eq. 30-31) already sees the next footholds over the 1.6 s horizon, and the MPC's "
        "plan (eq. 37) turns the pelvis toward the coming swing before the foot lifts (its "
        "rate reverses in the DSP). <b>Step: to lift-off</b> stops at the first instant the "
        "foot is off the ground (phase <i>SSP</i>): the turn the plan made before it. "
        "The table above is read from the frame shown (paused, the paused instant): the "
        "planned angle now and at the end of the horizon, and the waist rate now.",
        ("30", "31", "37"),
        ("phase", "plan", "rate_now", "waist", "liftoff"),
    ),
    Lesson(
        "3. What arm swing buys",
        "eq. 41-43; Fig. 12",
        {"step_length": 0.30, "step_time": 1.2},
        (FIXED, MPC),
        "follow",
        "The lesson starts with the arms still: each swinging leg twists the body about the "
        "vertical and the black yaw-momentum <b>arrow</b> over the head grows. Read the peak "
        "over the last two steps in the table, then tick <b>Arm swing</b> (Controls tab, "
        "folder <i>Arm swing</i>) and watch the peak fall as the arms cancel the legs' "
        f"momentum (eq. 43); the paper reports up to -{_P['arm_reduction_percent']:.0f} % in its "
        "experiment.",
        ("41", "43"),
        ("arms", "yaw", "waist", "falls"),
        {"arms": {"enabled": False}},
        now=lambda p: (
            "Arm swing is <b>on</b> now: the arms swing against the legs; compare the peak "
            "yaw momentum with the one you read with the arms still."
            if p.arms.enabled
            else "Arm swing is <b>off</b> now: the arms hang still."
        ),
    ),
    Lesson(
        "4. Horizon length and k_pel",
        "eq. 31-37; Fig. 7",
        {"step_length": 0.40, "step_time": 1.2},
        (MPC,),
        "top",
        "Two MPC robots side by side, alike but for <b>k_pel</b>, which scales the reference "
        "angle for a given foot-to-pelvis distance (eq. 31): 0.25 (the default) and 0.45 (the "
        "hollow marker, a darker orange). The one with 0.45 turns its pelvis further "
        f"(measured at 0.40 m: {_K['waist'][0]:.0f}° against {_K['waist'][1]:.0f}°), so its "
        f"legs reach less far and their kappa stays lower ({_K['kappa'][0]:.0f} against "
        f"{_K['kappa'][1]:.0f} at most). Read the waist, reach and kappa rows. Then choose "
        "<b>Sliders act on: k_pel 0.45</b> (Controls tab, above the parameter folders) and "
        "shorten its <b>Horizon H</b> (folder <i>CoM MPC</i>; both MPCs use it) to one "
        "step (1.2 s) or less: that robot no longer sees the next foothold in time and falls "
        f"within its first steps (measured: H = {_K['falls'][0][0]:g} s falls at "
        f"{_K['falls'][0][1]:.1f} s, {_K['falls'][1][0]:g} s at {_K['falls'][1][1]:.1f} s), "
        f"while the other keeps its 1.6 s; {FALL_HOLD_S:g} s after a fall both restart "
        "together. Choosing <i>Sliders act on: all robots</i> changes nothing by itself; the "
        "next slider you move then sets its value for both robots (a robot's own value of "
        "that slider is dropped).",
        ("31", "37"),
        ("differ", "settings", "waist", "reach", "kappa_legs", "status", "falls"),
        robot_forms=("mpc", "mpc,pelvis.k_pel=0.45@k_pel 0.45"),
    ),
    Lesson(
        "5. Redundancy vs the MPC's waist rate",
        "eq. 37-40; Fig. 8-9",
        {"step_length": 0.40, "step_time": 1.2},
        (REDUNDANCY, MPC),
        "follow",
        "Both robots turn the pelvis, differently. <b>Redundancy</b> (the waist is one more "
        "free IK joint) turns only once the foot swings, and its rate jumps at lift-off and "
        "landing; the <b>MPC</b> plans a smooth wave (the paper: "
        f"-{_P['waist_peak_deg']:.0f} to +{_P['waist_peak_deg']:.0f}° at "
        f"{_P['waist_peak_length']:g} m). Compare "
        "the waist range and the <b>peak change of the waist rate</b> (its sharpness); the peak "
        "rates themselves are alike on our robot. The Plots tab draws both (Fig. 8).",
        ("37", "39"),
        ("waist", "liftoff", "rate", "jerk", "yaw", "status"),
    ),
    Lesson(
        "6. Eq. 1-5 against what the robots reach",
        "eq. 1-5; Fig. 1-2",
        {"step_length": _EQ5, "step_time": 1.2},
        (FIXED, MPC),
        "side",
        f"{_EQ5:.2f} m is eq. 5 with the pelvis at {_EQ4['theta']:.0f}° as the paper evaluates "
        "it (the Kinematic analysis below). Our fixed pelvis walks further than the static eq. 4 "
        f"({_EQ4['eq4']:.3f} m): the stance hip "
        f"travels forward during the step, so our limits are fixed {_F:.2f} m, MPC {_M:.2f} m "
        f"(paper: {_PF:.2f} / {_PM:.2f} m). Here the fixed robot <b>falls</b> in its second "
        f"step: it lies where it fell, ringed in {_DANGER}, for {FALL_HOLD_S:g} s while the MPC "
        "walks "
        f"on with much less than {_EQ4['theta']:.0f}°, then both restart together. Compare the "
        "measured hip "
        "advance with eq. 2's l_pel sin(theta). Eq. 1-5 assume the leg is stretched straight at "
        "the limit: the row <i>what stops the IK</i> shows where that happens on the robot, the "
        "knee held at its straight limit (0°), and which robot reaches it.",
        ("2", "4", "5"),
        ("step", "hip", "waist", "reach", "active", "status", "falls"),
    ),
    Lesson(
        "7. A push: what the controller does",
        "eq. 10-18 (CoM MPC); no figure: the paper does not push",
        {"step_length": 0.30, "step_time": 1.2},
        (FIXED, REDUNDANCY, MPC),
        "front",
        "Open <b>Push a robot</b> (Controls tab) and push one robot sideways. The CoM MPC keeps "
        "its plan (its ZMP stays inside the support foot, eq. 18); the pelvis position "
        "(eq. 19) moves to bring the measured CoM back onto the planned one, but <b>nothing "
        "moves the footsteps</b>: a push the foot cannot absorb "
        f"topples the robot (try 300 N): it lies ringed in {_DANGER} for {FALL_HOLD_S:g} s, then "
        "every robot restarts together. In a terminal, <code>pelvic-walk push-study</code> "
        "measures the largest push each method survives (<code>pelvic-walk push-study "
        "--help</code> for the direction, duration and step length).",
        ("18",),
        ("pushing", "lateral", "status", "falls"),
    ),
    Lesson(
        "8. Your own pelvis",
        "eq. 27-40; the paper's question: how should the waist turn?",
        {"step_length": 0.40, "step_time": 1.2},
        (MPC,),
        "follow",
        "Write how the pelvis turns in one Python file: a subclass of <code>PelvisStrategy</code> "
        "with a <code>name</code> and <code>waist_rate(self, s)</code>, which returns the waist "
        "yaw rate [rad/s] the IK pins each 5 ms tick (or <code>None</code>: free to the IK). "
        "<code>s</code> holds the waist now (<code>s.theta</code>), the paper's reference over "
        "the horizon (<code>s.theta_ref</code>, eq. 27-33), the predicted CoM, the planned "
        "feet and which foot swings (docs/STRATEGIES.md lists them; "
        "<code>examples/my_pelvis.py</code> is a template). Start the server with "
        "<code>pelvic-walk serve --strategy my_pelvis.py</code>: your robot walks here beside "
        "the MPC, in its own colour. Compare, at 0.40 m: how far it turns (waist range), how "
        "much of that it turns <b>before</b> the swing (the share in the double support: the "
        "paper's point), how sharply (peak change of the rate), what it costs in yaw momentum, "
        "and whether its badge stays <i>clean</i>; then raise the <b>Step length</b> until it "
        "is not. (Tick the fixed pelvis in <i>Compare</i> to see it too: past 0.42 m it falls, "
        "and every fall restarts all robots.) If your code raises or returns no number, your "
        "robot stops with the file and line on its label while the others walk on; <b>Restart "
        "all robots together</b> runs it again.",
        ("30", "37", "39"),
        ("status", "waist", "dsp_turn", "liftoff", "jerk", "yaw", "reach", "falls"),
        now=lambda _p: own_strategies_sentence(),
        own=True,
    ),
    Lesson(
        "9. What beta_pel buys",
        "eq. 34-37; Fig. 7",
        {"step_length": 0.40, "step_time": 1.2},
        (MPC,),
        "top",
        "Two MPC robots alike but for <b>beta_pel</b>, the weight on the pelvis's yaw "
        "acceleration in the pelvic MPC's cost (eq. 36): 1e-6 (the default) and 0.01 (the "
        "hollow marker). With a small beta_pel the optimised angle (eq. 37) lies on the "
        "reference: in the Inspect tab the plan is drawn right on top of the reference. "
        "Raised, the acceleration costs and the plan smooths the reference: open the "
        "<b>Inspect</b> tab, choose each robot in its "
        f"<i>Robot</i> list and compare the {_PREDICTED} plan with the {_REFERENCE} dashed "
        "reference; the table's <i>MPC angle</i> row and the peak change of the waist rate "
        "say it in numbers. Both walk at 0.40 m (measured: the waist turns about "
        f"±{_B['waist'][0]:.1f}° and ±{_B['waist'][1]:.1f}°). The smoother plan turns the "
        "pelvis less, so the legs reach further and their kappa is higher (about "
        f"{_B['kappa'][1]} against {_B['kappa'][0]} at most). Move the <b>beta_pel</b> slider "
        "(folder <i>Pelvic MPC</i>) with <i>Sliders act on</i> set to one robot to try other "
        "values beside it.",
        ("37",),
        ("differ", "plan", "waist", "rate", "jerk", "kappa_legs", "status"),
        robot_forms=("mpc", "mpc,pelvis.beta=0.01@beta_pel 0.01"),
    ),
)


def own_strategies_sentence() -> str:
    """Lesson 8's first sentence: which strategies of the students' this server runs."""
    users = [strategy.info(n) for n in strategy.names() if not strategy.info(n).builtin]
    if not users:
        return (
            "This server runs <b>no strategy of yours</b> yet: only the paper's methods walk. "
            "Stop it and start <code>pelvic-walk serve --strategy examples/track_reference.py"
            "</code> (or your own file) to see one beside them."
        )
    names = ", ".join(f"<b>{i.label}</b> ({os.path.basename(i.file or '')})" for i in users)
    return f"Running your strategies: {names}."


# Short lessons, one per layer, with the paper's equation numbers.
EXPLAIN: dict[str, str] = {
    "Overview": (
        "Each robot runs the same controller, by default with the same parameters; only the "
        "**waist yaw** "
        "(the pelvic rotation) differs: **fixed** keeps it at 0, **redundancy** (ref. [21]) "
        "lets the IK use it with no preview, the **pelvic-rotation MPC** plans it over the "
        "horizon. Raise the step length and watch the **reach gauges**: the fixed pelvis "
        f"straightens its swing leg ({_DANGER}) first. A robot may also have settings of its "
        "own (the Compare folder adds one: an MPC with a shorter horizon beside the MPC); its "
        "label says how it differs, and *Sliders act on* chooses whether a slider moves one robot "
        "or all."
    ),
    "CoM MPC (eq. 10-18)": (
        "A linear inverted pendulum at constant height, state [p, v, a] per axis, input = jerk "
        "(eq. 10-12). Over the horizon H it trades **alpha** x ZMP tracking, **beta** x CoM "
        "velocity changes and **gamma** x jerk (eq. 18), keeping the ZMP inside the support "
        f"area. The **{_PREDICTED}** path on the floor is its predicted CoM (eq. 25-26)."
    ),
    "Pelvis position (eq. 19)": (
        "The pelvis follows the desired CoM and corrects the offset to the CoM measured from "
        "the joint angles with gain K_p (eq. 19). Its orientation stays 0: the torso faces "
        "forward while the waist joint turns the hips."
    ),
    "Feet (eq. 20-21)": (
        "The support foot stays on its foothold; the swing foot follows a cubic from the old "
        "to the new foothold with zero velocity at both ends, plus a smooth lift (eq. 20-21). "
        "The grey curve (Layers: Swing-foot path) is the path of the swing in progress; the grey "
        "rectangles are the planned footholds (0.30 x 0.17 m feet)."
    ),
    "Reference pelvic angle (eq. 27-33)": (
        "At each predicted sample the pelvis is put at the predicted CoM (eq. 27) and the angle "
        "is the mean over both feet of atan(k_pel dx / dy) (eq. 28-33), signed so each hip "
        f"turns **toward its own foot**. The **{_REFERENCE} dashed hip lines** on the floor "
        "show it "
        "over the horizon."
    ),
    "Pelvic-rotation MPC (eq. 34-38)": (
        "A double integrator theta'' = u tracks the reference with weight **alpha_pel** and "
        "penalises u with **beta_pel**, with |theta| under the angle limit (eq. 34-38). The "
        f"**{_PREDICTED} solid hip lines** are its optimised angles: it starts turning "
        "*before* the "
        "swing. At small beta_pel they lie on the reference's (the Inspect tab says why)."
    ),
    "QP inverse kinematics (eq. 39-40)": (
        "13 joint velocities (waist yaw + two legs) make the feet follow their paths: "
        "min ||J q' - x'_feet||^2 with joint and speed limits (eq. 39-40). The waist rate is "
        "pinned to 0 (fixed), free (redundancy) or the MPC's rate (mpc). The **leg colours** "
        f"show the reach: hip-to-ankle distance / leg length, {_DANGER} near 1 (straight knee)."
    ),
    "Arm swing (eq. 41-43)": (
        "The arms cancel the legs' yaw momentum: min omega1 (h_low + h_up)^2 + omega2 "
        "||q_up0 - q_up||^2 + omega3 ||q'_up||^2 on the centroidal momentum matrix "
        "(eq. 41-43). The black **arrow** over the head is the whole-body yaw momentum."
    ),
    "Energy and kappa (eq. 44-45)": (
        "Energy = sum of the positive joint work per two-step window (eq. 44). kappa(J) is the "
        "condition number of the leg Jacobian (eq. 45): it shoots up as a knee straightens."
    ),
    "Kinematic analysis (eq. 1-5)": (
        "Static step limit of a stretched leg: sqrt(l_leg^2 - z0^2) (eq. 4, "
        f"{_EQ4['eq4']:.3f} m). Turning the pelvis moves the swing hip ahead (eq. 2, 5): "
        f"{_EQ4['eq5_printed']:.3f} m with eq. 5 as printed (0.5 l_pel sin theta), "
        f"{_EQ4['eq5_paper']:.3f} m (+{_EQ4['gain_paper']:.0f} %) as the paper evaluates it (its "
        f"{_EQ5:.2f} m). "
        "Turn the pelvis with the slider of the Kinematic analysis folder."
    ),
}


def warnings_for(params: Any, methods: tuple[str, ...] = BUILTINS) -> list[str]:
    """Settings known to break walking, explained in one line each (empty when none), for
    the robots shown (``methods``)."""
    w = params.walk
    out = []
    if params.com.horizon < w.step_time:
        out.append(
            f"The MPC horizon ({params.com.horizon:.1f} s) is shorter than one step "
            f"({w.step_time:.2f} s): the CoM MPC cannot see the next support foot before the "
            "step starts, so the CoM arrives late and the robots tend to fall."
        )
    if w.dsp_ratio * w.step_time < 0.1:
        out.append(
            f"A double support of {1000 * w.dsp_ratio * w.step_time:.0f} ms leaves the CoM "
            "very little time to move to the new support foot."
        )
    if params.pelvis.k_pel == 0.0 and MPC in methods:
        out.append("k_pel = 0: the reference pelvic angle is 0, the MPC plans no rotation.")
    names = {FIXED: FIXED, REDUNDANCY: REDUNDANCY, MPC: "MPC"}
    shown = [m for m in BUILTINS if m in methods]  # the limits measured: the paper's three
    beyond = [m for m in shown if w.step_length > CLEAN_LIMIT_M[m] + 1e-9]
    if beyond:
        limits = ", ".join(f"{names[m]} {CLEAN_LIMIT_M[m]:.2f} m" for m in shown)
        out.append(
            f"{w.step_length:.2f} m is beyond the longest clean step measured on this robot for "
            f"{', '.join(names[m] for m in beyond)} ({limits} at 1.2 s steps): watch the "
            "status badges."
        )
    return out
