"""A second idea: turn the pelvis by a sine at the step frequency, planned in advance.

It reads neither the reference nor the predicted CoM, only which foot swings and when the
step began. Over a left step the waist goes from +A (left hip back, the left foot behind) to
-A (left hip ahead, the left foot landing in front), and back over a right step, with the
amplitude of eq. (31)-(32) at touch-down: A = atan(k_pel * step_length / step_width).

    pelvic-walk simulate --strategy examples/feedforward_sine.py --step-length 0.4
"""

import math

from pelvic_walk import PelvisStrategy

CATCH_UP = 5.0  # [1/s] pulls the waist onto the sine when it is off it (the first step)


class FeedForwardSine(PelvisStrategy):
    """A sine over each step, +A to -A over a left step and back over a right one."""

    name = "sine"
    label = "feed-forward sine"

    def reset(self, s):
        self.step, self.step_began = s.step, s.t  # the step in progress and its start [s]

    def waist_rate(self, s):
        if s.step != self.step:  # a new step began this tick
            self.step, self.step_began = s.step, s.t
        if s.swing is None:  # standing: back to 0
            return -CATCH_UP * s.theta
        walk = s.params.walk
        amplitude = math.atan(s.params.pelvis.k_pel * walk.step_length / walk.step_width)
        sign = 1.0 if s.swing == "left" else -1.0
        w = math.pi / walk.step_time  # [rad/s] half a cycle per step
        tau = s.t - self.step_began  # [s] into the step
        target = sign * amplitude * math.cos(w * tau)  # [rad]
        target_rate = -sign * amplitude * w * math.sin(w * tau)  # [rad/s]
        return target_rate + CATCH_UP * (target - s.theta)
