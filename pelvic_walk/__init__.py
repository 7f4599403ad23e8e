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

    @dataclass(frozen=True)
    class Gain:
        k: float = pw.param(8.0, min=0.0, max=40.0, unit="1/s", label="gain k")

    class TrackWithGain(pw.PelvisStrategy):
        name = "gain"
        Params = Gain  # its own parameters: a slider, --set gain.k=V, **{"gain.k": V}

        def waist_rate(self, s):
            return self.params.k * (s.theta_ref[0] - s.theta)  # [rad/s]

    mine = pw.simulate(strategy=TrackWithGain, step_length=0.35, steps=4, **{"gain.k": 12})

Drive a served tool (``pelvic-walk serve``): ``pw.Client("http://127.0.0.1:8000")``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# Each public name and the module that defines it, imported when first used (PEP 562): the
# faces import the core (``pelvic_walk.core``) through this package, and a command line or a
# live worker that needs a walk does not load the HTTP client or the plots with it.
_WHERE = {
    "PelvisStrategy": "controller.strategy",
    "param": "controller.params",
    "StrategyError": "controller.strategy",
    "StrategyInputs": "controller.strategy",
    "StrategyLoadError": "controller.strategy",
    "ApiError": "pelvic_walk._client",
    "Busy": "pelvic_walk._client",
    "Client": "pelvic_walk._client",
    "Conflict": "pelvic_walk._client",
    "InvalidRequest": "pelvic_walk._client",
    "NotAllowed": "pelvic_walk._client",
    "NotFound": "pelvic_walk._client",
    "DEFAULT_PANELS": "pelvic_walk._plots",
    "PANELS": "pelvic_walk._plots",
    "plot": "pelvic_walk._plots",
    "Player": "pelvic_walk._run",
    "Run": "pelvic_walk._run",
    "analyze": "pelvic_walk._run",
    "compare": "pelvic_walk._run",
    "robot": "pelvic_walk._run",
    "simulate": "pelvic_walk._run",
    "sweep": "pelvic_walk._sweep",
}

if TYPE_CHECKING:
    from controller.params import param
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


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'pelvic_walk' has no attribute {name!r}")
    value = getattr(importlib.import_module(where), name)
    globals()[name] = value  # once: later lookups do not come here
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


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
    "param",
    "plot",
    "robot",
    "simulate",
    "strategies",
    "sweep",
]
