"""pelvic-walk from Python: the public names (everything else is internal). docs/PYTHON.md
is the guide; ``notebooks/`` the course.

Walk, look, compare::

    import pelvic_walk as pw

    mpc = pw.simulate("mpc", step_length=0.35, steps=4)
    fixed = pw.simulate("fixed", step_length=0.35, steps=4)
    pw.compare([fixed, mpc])          # one table (pandas)
    mpc.plot(others=[fixed])          # waist, rate, yaw momentum, kappa, energy
    mpc.show()                        # the 3-D scene, in a notebook

Write how the pelvis turns (docs/STRATEGIES.md) and run it beside the paper's MPC::

    class TrackWithGain(pw.PelvisStrategy):
        name = "gain"

        def waist_rate(self, s):
            return 8.0 * (s.theta_ref[0] - s.theta)  # [rad/s]

    mine = pw.simulate(strategy=TrackWithGain, step_length=0.35, steps=4)

Drive a served tool (``pelvic-walk serve``): ``pw.Client("http://127.0.0.1:8000")``.
"""

from controller.strategy import (
    PelvisStrategy,
    StrategyError,
    StrategyInputs,
    StrategyLoadError,
)
from pelvic_walk._client import (
    ApiError,
    Busy,
    Client,
    Conflict,
    InvalidRequest,
    NotAllowed,
    NotFound,
)
from pelvic_walk._plots import DEFAULT_PANELS, PANELS, plot
from pelvic_walk._run import Player, Run, analyze, compare, robot, simulate
from pelvic_walk._sweep import sweep


def strategies() -> list[str]:
    """The names ``method=`` takes now: the paper's three, then those loaded or defined."""
    from controller import strategy

    return list(strategy.names())


__all__ = [
    "DEFAULT_PANELS",
    "PANELS",
    "ApiError",
    "Busy",
    "Client",
    "Conflict",
    "InvalidRequest",
    "NotAllowed",
    "NotFound",
    "PelvisStrategy",
    "Player",
    "Run",
    "StrategyError",
    "StrategyInputs",
    "StrategyLoadError",
    "analyze",
    "compare",
    "plot",
    "robot",
    "simulate",
    "strategies",
    "sweep",
]
