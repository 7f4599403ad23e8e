"""Your own pelvis strategy: copy this file, fill in waist_rate, run it beside the MPC.

    pelvic-walk simulate --strategy my_pelvis.py --step-length 0.3
    pelvic-walk serve --strategy my_pelvis.py     # a fourth robot, in its own colour

What `s` holds (all read-only; docs/STRATEGIES.md has the full list with units and frames):
    s.t, s.dt                  [s] time since the walk began, the control period (0.005)
    s.theta, s.theta_dot       [rad], [rad/s] the waist yaw now (+ turns the left hip back)
    s.theta_ref                (N,) [rad] the paper's reference angle (eq. 27-33) ahead
    s.horizon_t                (N,) [s] when those samples are, from now
    s.com                      (N, 2) [m] the CoM the CoM MPC predicts (eq. 25-26)
    s.left_sole, s.right_sole  (N, 3) [m] the planned feet ahead (and *_now: (3,) now)
    s.support, s.swing         "left" / "right" / "both", the swinging foot (None standing)
    s.step, s.phase            step in progress, 0..1 through its single support
    s.params                   every parameter in force (s.params.walk.step_length, ...)
"""

from pelvic_walk import PelvisStrategy


class MyPelvis(PelvisStrategy):
    """One line about your idea (shown in the tool's list of strategies)."""

    name = "mine"  # the robot's key and label: letters, digits, _ . -
    # label = "a few words"        # optional: shown on the robot's tag
    # color = (200, 60, 150)       # optional: RGB 0-255

    def reset(self, s):
        """Optional: called when each walk starts. Clear what you keep between ticks."""

    def waist_rate(self, s):
        """The waist yaw rate [rad/s] the IK pins this tick, or None to leave it free."""
        return 0.0  # the fixed pelvis: replace with your idea
