"""pelvic-walk from Python: the public names (everything else is internal).

Write how the pelvis turns in a file of your own (docs/STRATEGIES.md)::

    from pelvic_walk import PelvisStrategy

    class TrackWithGain(PelvisStrategy):
        name = "gain"

        def waist_rate(self, s):
            return 8.0 * (s.theta_ref[0] - s.theta)  # [rad/s]

and run it beside the paper's MPC: ``pelvic-walk simulate --strategy my_pelvis.py
--step-length 0.3``, ``pelvic-walk serve --strategy my_pelvis.py``.
"""

from controller.strategy import (
    PelvisStrategy,
    StrategyError,
    StrategyInputs,
    StrategyLoadError,
)

__all__ = ["PelvisStrategy", "StrategyError", "StrategyInputs", "StrategyLoadError"]
