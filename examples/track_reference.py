"""A first idea: follow the paper's reference pelvic angle with a plain gain.

No optimisation and no look at the future of the reference: each tick the waist turns toward
theta_ref's first sample (one MPC sample ahead) at a rate proportional to the error. Run it
beside the paper's MPC, which plans the same reference over the whole horizon:

    pelvic-walk simulate --strategy examples/track_reference.py --step-length 0.4
    pelvic-walk serve --strategy examples/track_reference.py

Its gain is a parameter of its own (``Params`` below): a slider in its folder of the panel,
``--set track_ref.gain=12`` on the command line, a sweep's axis:

    pelvic-walk sweep --strategy examples/track_reference.py --methods track_ref \\
        --set track_ref.gain=4,8,16 --measure summary --out sweep
"""

from dataclasses import dataclass

from pelvic_walk import PelvisStrategy, param


class TrackReference(PelvisStrategy):
    """Tracks theta_ref (eq. 27-33) with a proportional gain: no prediction of its own."""

    name = "track_ref"
    label = "gain on theta_ref"

    @dataclass(frozen=True)
    class Params:
        # a turn of error e [rad] is closed at e * gain rad/s: 8 is a 0.125 s lag
        gain: float = param(
            8.0,
            min=0.0,
            max=40.0,
            step=0.5,
            unit="1/s",
            label="gain on the error",
            help="rate per radian of error to theta_ref[0]; 0 holds the waist still",
        )

    def waist_rate(self, s):
        return self.params.gain * (s.theta_ref[0] - s.theta)  # [rad/s]
