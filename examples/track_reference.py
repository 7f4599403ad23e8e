"""A first idea: follow the paper's reference pelvic angle with a plain gain.

No optimisation and no look at the future of the reference: each tick the waist turns toward
theta_ref's first sample (one MPC sample ahead) at a rate proportional to the error. Run it
beside the paper's MPC, which plans the same reference over the whole horizon:

    pelvic-walk simulate --strategy examples/track_reference.py --step-length 0.4
    pelvic-walk serve --strategy examples/track_reference.py
"""

from pelvic_walk import PelvisStrategy

GAIN = 8.0  # [1/s] a turn of error e [rad] is closed at e * GAIN rad/s: a 0.125 s lag


class TrackReference(PelvisStrategy):
    """Tracks theta_ref (eq. 27-33) with a proportional gain: no prediction of its own."""

    name = "track_ref"
    label = "gain on theta_ref"

    def waist_rate(self, s):
        return GAIN * (s.theta_ref[0] - s.theta)  # [rad/s]
