"""The paper's equations as MathML and the kinematic analysis drawn as its Fig. 1-2 (SVG).

viser's markdown has no LaTeX, but its HTML element is rendered by Chromium, which supports
MathML Core: every equation here is a ``<math>`` element built from a few helpers, checked
as XML by the tests. :func:`analysis_svg` draws eq. (1)-(5) for a pelvic angle.
"""

from __future__ import annotations

import math

from app.web import lesson_numbers
from controller.strategy import FIXED, MPC


# -- a tiny MathML builder ----------------------------------------------------------------------
def _el(tag: str, *children: str) -> str:
    return f"<{tag}>{''.join(children)}</{tag}>"


def mi(x: str) -> str:
    return _el("mi", x)


def mn(x: str) -> str:
    return _el("mn", x)


def mo(x: str) -> str:
    return _el("mo", x)


def row(*c: str) -> str:
    return _el("mrow", *c)


def sub(base: str, s: str) -> str:
    return _el("msub", base, s)


def sup(base: str, s: str) -> str:
    return _el("msup", base, s)


def subsup(base: str, s: str, p: str) -> str:
    return _el("msubsup", base, s, p)


def frac(a: str, b: str) -> str:
    return _el("mfrac", a, b)


def sqrt(*c: str) -> str:
    return _el("msqrt", *c)


def txt(x: str) -> str:
    return _el("mtext", x)


def par(*c: str) -> str:
    return row(mo("("), *c, mo(")"))


def norm2(*c: str) -> str:
    return sup(row(mo("‖"), *c, mo("‖")), mn("2"))


def dot(x: str) -> str:
    return _el("mover", mi(x), mo("˙"))


def ddot(x: str) -> str:
    return _el("mover", mi(x), mo("¨"))


SPACE = '<mspace width="1em"></mspace>'
_BLOCK = "font-size:0.95em;margin:3px 0;max-width:100%;overflow-x:auto"


def eq(number: str, *c: str) -> str:
    """A block equation with its number, as printed in the paper."""
    return f'<math display="block" style="{_BLOCK}">{row(*c, SPACE, txt(f"({number})"))}</math>'


def label(x: str) -> str:
    """Words before a formula (MathML drops a text's trailing spaces: add a real space)."""
    return txt(x) + '<mspace width="0.5em"></mspace>'


def more(*c: str) -> str:
    """A continuation line of the equation above (side conditions, further terms): the
    panel is narrow, so long equations wrap by hand."""
    return f'<math display="block" style="{_BLOCK}">{row(*c)}</math>'


THETA = sub(mi("θ"), mi("pel"))
L_LEG, Z0, L_PEL = sub(mi("l"), mi("leg")), sub(mi("z"), mn("0")), sub(mi("l"), mi("pel"))
REACH = sqrt(sup(L_LEG, mn("2")), mo("−"), sup(Z0, mn("2")))
STEP_FIXED = subsup(mi("l"), mi("stepmax"), txt("*fixed"))
STEP_ROT = subsup(mi("l"), mi("stepmax"), txt("*rotation"))
D_HC = subsup(mi("Δd"), mi("hc"), mo("*"))
Q_LOW, Q_UP = sub(dot("q"), mi("low")), sub(dot("q"), mi("up"))
H_LOW, H_UP = subsup(mi("h"), mi("low"), mi("yaw")), subsup(mi("h"), mi("up"), mi("yaw"))

EQUATIONS: dict[str, str] = {
    "1": eq("1", STEP_FIXED, mo("="), mn("2"), REACH),
    "2": eq("2", sub(mi("Δd"), mi("hip")), mo("="), L_PEL, mo("⋅"), mi("sin"), THETA),
    "3": eq(
        "3",
        STEP_ROT,
        mo("="),
        sqrt(
            sup(par(subsup(mi("l"), mi("max"), mi("step")), mo("+"), L_PEL), mn("2")),
            mo("−"),
            sup(sub(mi("w"), mi("step")), mn("2")),
        ),
    ),
    "4": eq("4", STEP_FIXED, mo("="), REACH),
    "5": eq("5", STEP_ROT, mo("="), REACH, mo("+"), D_HC)
    + more(label("as printed:"), D_HC, mo("="), mn("0.5"), L_PEL, mi("sin"), THETA),
    "18": eq(
        "18",
        mi("min"),
        mi("α"),
        norm2(sub(mi("Z"), mi("ref")), mo("−"), mi("Z")),
        mo("+"),
        mi("β"),
        norm2(mi("Δ"), dot("C")),
        mo("+"),
        mi("γ"),
        norm2(_el("mover", mi("C"), mo("⃛"))),
    )
    + more(
        label("s.t."), sub(mi("Z"), mi("min")), mo("≤"), mi("Z"), mo("≤"), sub(mi("Z"), mi("max"))
    ),
    "30": eq(
        "30",
        subsup(mi("θ"), mi("pel"), mi("ref")),
        par(mi("k")),
        mo("="),
        frac(
            row(
                sub(mi("θ"), mi("LFP")),
                par(mi("k")),
                mo("+"),
                sub(mi("θ"), mi("RFP")),
                par(mi("k")),
            ),
            mn("2"),
        ),
    ),
    "31": eq(
        "31",
        sub(mi("θ"), mi("LFP")),
        par(mi("k")),
        mo("="),
        sup(mi("tan"), mn("−1")),
        par(
            frac(
                row(sub(mi("k"), mi("pel")), sub(mi("Δd"), mi("LFP,x")), par(mi("k"))),
                sub(mi("Δd"), mi("LFP,y")),
            )
        ),
    ),
    "37": eq(
        "37",
        sub(mi("min"), ddot("Θ")),
        sub(mi("α"), mi("pel")),
        norm2(mi("Θ"), mo("−"), subsup(mi("Θ"), mi("pel"), mi("ref"))),
        mo("+"),
        sub(mi("β"), mi("pel")),
        norm2(ddot("Θ")),
    )
    + more(label("s.t."), mo("|"), mi("Θ"), mo("|"), mo("≤"), sub(mi("Θ"), mi("max"))),
    "39": eq(
        "39",
        sub(mi("min"), Q_LOW),
        frac(mn("1"), mn("2")),
        norm2(sub(mi("J"), mi("low")), Q_LOW, mo("−"), sub(dot("X"), mi("f,d"))),
    )
    + more(
        label("s.t."),
        sub(dot("q"), mi("wy")),
        mo("="),
        sub(dot("θ"), row(mi("i"), mo("+"), mn("1"))),
        SPACE,
        txt("(mpc; 0 fixed, free redundancy)"),
    ),
    "41": eq("41", H_LOW, mo("="), subsup(mi("A"), mi("low,yaw"), mi("CMM")), Q_LOW),
    "43": eq(
        "43",
        sub(mi("min"), Q_UP),
        frac(sub(mi("ω"), mn("1")), mn("2")),
        norm2(H_LOW, mo("+"), H_UP),
        mo("+"),
        frac(sub(mi("ω"), mn("2")), mn("2")),
        norm2(subsup(mi("q"), mi("up"), mi("init")), mo("−"), sub(mi("q"), mi("up"))),
    )
    + more(mo("+"), frac(sub(mi("ω"), mn("3")), mn("2")), norm2(Q_UP)),
    "45": eq(
        "45",
        mi("κ"),
        par(mi("J")),
        mo("="),
        frac(sub(mi("σ"), mi("max")), sub(mi("σ"), mi("min"))),
    ),
}


def equations(*numbers: str) -> str:
    """The named equations, one block each."""
    return "".join(EQUATIONS[n] for n in numbers)


# -- the kinematic analysis, drawn as Fig. 1-2 ----------------------------------------------------
FOOT_L, FOOT_W = 0.30, 0.17  # [m] our sole (the paper's robot has about the same)


def analysis_numbers(theta_deg: float) -> dict[str, float]:
    """Eq. (2), (4), (5) at ``theta_deg`` with the paper's inputs, both readings of eq. (5)."""
    from controller.analysis import hip_centre_offset, kinematic_analysis

    ka = kinematic_analysis()
    reach = ka["step_max_fixed_static"]  # eq. (4)
    printed = hip_centre_offset(ka["l_pel"], theta_deg, "literal")  # 0.5 l_pel sin theta
    paper = hip_centre_offset(ka["l_pel"], theta_deg, "paper")  # l_pel sin theta cos theta
    return {
        **ka,
        "theta": theta_deg,
        "eq4": reach,
        "hip_advance": ka["l_pel"] * math.sin(math.radians(theta_deg)),  # eq. (2)
        "dhc_printed": printed,
        "dhc_paper": paper,
        "eq5_printed": reach + printed,
        "eq5_paper": reach + paper,
        "gain_printed": 100.0 * printed / reach,
        "gain_paper": 100.0 * paper / reach,
    }


def analysis_svg(theta_deg: float) -> str:
    """Fig. 1-2 for a pelvis turned by ``theta_deg``: the top (x-y) view with the feet and the
    turned pelvis, the side (x-z) view with the stretched swing leg, and eq. (4), (5)."""
    n = analysis_numbers(theta_deg)
    t = math.radians(theta_deg)
    l_pel, reach, z0, w = n["l_pel"], n["eq4"], n["z0"], n["w_step"]
    s, ox = 300.0, 50.0  # px per m (x and the top view's y); x of the pelvis centre
    top_y, side_y, zs = 102.0, 298.0, 100.0  # top view's centre line, side view's floor [px];
    # px per m in z (a third of x: the whole leg fits; the step lengths are read along x)

    def tx(x: float) -> float:
        return ox + s * x

    def ty(y: float) -> float:  # top view: +y (the robot's left) up
        return top_y - s * y

    hl = (-0.5 * l_pel * math.sin(t), 0.5 * l_pel * math.cos(t))  # left (support) hip
    hr = (0.5 * l_pel * math.sin(t), -0.5 * l_pel * math.cos(t))  # right (swing) hip
    x4, x5p, x5 = reach, hr[0] + reach, n["eq5_paper"]  # ankle of the landing foot [m]
    hip_z = side_y - zs * z0

    def foot(x: float, y: float, style: str) -> str:
        return (
            f'<rect x="{tx(x - FOOT_L / 2):.1f}" y="{ty(y + FOOT_W / 2):.1f}" '
            f'width="{s * FOOT_L:.1f}" height="{s * FOOT_W:.1f}" rx="3" {style}/>'
        )

    def tick(x: float, colour: str) -> str:  # where the landing ankle would be, top view
        y0, y1 = ty(-w / 2 + FOOT_W / 2 + 0.02), ty(-w / 2 - FOOT_W / 2 - 0.02)
        return (
            f'<line x1="{tx(x):.1f}" y1="{y0:.1f}" x2="{tx(x):.1f}" y2="{y1:.1f}" '
            f'stroke="{colour}" stroke-width="2" stroke-dasharray="3 2"/>'
        )

    def bar(row: int, x: float, colour: str, label: str) -> str:  # a step length under the floor
        y = side_y + 9 + 10 * row
        return (
            f'<line x1="{tx(0):.1f}" y1="{y:.1f}" x2="{tx(x):.1f}" y2="{y:.1f}" '
            f'stroke="{colour}" stroke-width="3"/>'
            f'<text x="{tx(x) + 4:.1f}" y="{y + 3.5:.1f}" fill="{colour}">{label}</text>'
        )

    return f"""
<svg viewBox="0 0 340 332" width="100%" xmlns="http://www.w3.org/2000/svg"
     style="font: 10.5px sans-serif; background: #f6f7f9; border-radius: 6px">
  <text x="6" y="14" font-weight="bold">top (x-y): pelvis turned {theta_deg:.0f}°, walking →</text>
  {foot(0.0, w / 2, 'fill="#4682ff22" stroke="#4682ff" stroke-width="1.5"')}
  <text x="{tx(-0.13):.1f}" y="{ty(w / 2) + 4:.1f}" fill="#4682ff">support foot</text>
  {foot(x5p, -w / 2, 'fill="#28b46422" stroke="#28b464" stroke-width="2"')}
  {tick(x4, "#80868b")}
  {tick(x5, "#e8710a")}
  <line x1="{tx(hr[0]):.1f}" y1="{ty(hr[1]):.1f}" x2="{tx(x5p):.1f}" y2="{ty(-w / 2):.1f}"
        stroke="#ff5050" stroke-width="2"/>
  <line x1="{tx(hl[0]):.1f}" y1="{ty(hl[1]):.1f}" x2="{tx(hr[0]):.1f}" y2="{ty(hr[1]):.1f}"
        stroke="#444" stroke-width="5" stroke-linecap="round"/>
  <circle cx="{tx(hl[0]):.1f}" cy="{ty(hl[1]):.1f}" r="5" fill="#4682ff"/>
  <circle cx="{tx(hr[0]):.1f}" cy="{ty(hr[1]):.1f}" r="5" fill="#ff5050"/>
  <text x="6" y="184" fill="#ff5050">swing hip {1000 * hr[0]:+.0f} mm ahead of the centre;
    hips {1000 * n["hip_advance"]:.0f} mm apart (eq. 2)</text>
  <line x1="6" y1="194" x2="334" y2="194" stroke="#d0d3d7"/>
  <text x="6" y="209" font-weight="bold">side (x-z): swing knee straight at landing</text>
  <line x1="6" y1="{side_y:.1f}" x2="334" y2="{side_y:.1f}" stroke="#888"/>
  <line x1="{tx(0):.1f}" y1="{hip_z:.1f}" x2="{tx(0):.1f}" y2="{side_y:.1f}" stroke="#4682ff"
        stroke-width="3"/>
  <line x1="{tx(0):.1f}" y1="{hip_z:.1f}" x2="{tx(x4):.1f}" y2="{side_y:.1f}" stroke="#80868b"
        stroke-width="2.5" stroke-dasharray="5 3"/>
  <line x1="{tx(hr[0]):.1f}" y1="{hip_z:.1f}" x2="{tx(x5p):.1f}" y2="{side_y:.1f}"
        stroke="#28b464" stroke-width="3"/>
  <circle cx="{tx(0):.1f}" cy="{hip_z:.1f}" r="4" fill="#444"/>
  <circle cx="{tx(hr[0]):.1f}" cy="{hip_z:.1f}" r="4" fill="#ff5050"/>
  <text x="{tx(x5p) + 6:.1f}" y="{hip_z + 12:.1f}" fill="#5f6368">hip height z0 {z0} m,</text>
  <text x="{tx(x5p) + 6:.1f}" y="{hip_z + 25:.1f}" fill="#5f6368">leg {n["l_leg"]} m,
    z at 1/3 scale</text>
  {bar(0, x4, "#80868b", f"eq. 4: {x4:.3f} m")}
  {bar(1, x5p, "#1e8e3e", f"eq. 5 printed: {n['eq5_printed']:.3f} m")}
  {bar(2, x5, "#e8710a", f"paper's reading: {x5:.3f} m")}
</svg>"""


def analysis_html(theta_deg: float, clean_limits: dict[str, float]) -> str:
    """The drawing with the numbers and what they mean (one percentage per reading)."""
    n = analysis_numbers(theta_deg)
    ours = 100.0 * (clean_limits[MPC] / clean_limits[FIXED] - 1.0)
    k, lim = lesson_numbers.paper()["kinematics"], lesson_numbers.paper_limits()
    theta_p = lesson_numbers.paper()["robot"]["theta_pel_deg"]
    return f"""{analysis_svg(theta_deg)}
<div style="font: 12.5px/1.45 sans-serif; margin-top: 6px">
<b>Eq. 4</b> (pelvis fixed, knee straight at landing): <b>{n["eq4"]:.3f} m</b>.<br/>
<span style="color:#1e8e3e"><b>Eq. 5 as printed</b>, Δd*<sub>hc</sub> = 0.5 l<sub>pel</sub>
sin θ = {1000 * n["dhc_printed"]:.0f} mm: <b>{n["eq5_printed"]:.3f} m</b>
(+{n["gain_printed"]:.0f} %)</span>; that is what the drawing shows: turning about its centre,
the swing hip moves ahead by half of eq. 2's hip advance.<br/>
<span style="color:#e8710a"><b>The reading that gives the paper's {k["step_max_rotation"]:.2f} m</b>
(at {theta_p:.0f}°):
Δd*<sub>hc</sub> = l<sub>pel</sub> sin θ cos θ = {1000 * n["dhc_paper"]:.0f} mm:
<b>{n["eq5_paper"]:.3f} m</b> (+{n["gain_paper"]:.0f} %)</span>.<br/>
<b>Eq. 2</b>: the hips are l<sub>pel</sub> sin θ = {1000 * n["hip_advance"]:.0f} mm apart
along x, but the step gains only the swing hip's lead over the pelvis centre (which stays over
the support foot): half of it as printed, up to l<sub>pel</sub>/2 = {500 * n["l_pel"]:.0f} mm
as the paper evaluates it.<br/>
At {theta_p:.0f}° the paper's reading gives +{kinematic_gain():.0f} %
(the paper writes +{k["increase_percent"]:.0f} %, from the rounded
{k["step_max_rotation"]:.2f} / {k["step_max_fixed"]:.2f}). Our robots, closed loop: fixed
{clean_limits["fixed"]:.2f} m, MPC {clean_limits["mpc"]:.2f} m walked cleanly (+{ours:.0f} %;
paper: {lim["fixed"]:.2f} / {lim["mpc"]:.2f} m).
</div>"""


def kinematic_gain() -> float:
    """[%] eq. (5) over eq. (4) at 45° as the paper evaluates it, unrounded (+33 %)."""
    from controller.analysis import kinematic_analysis

    return float(kinematic_analysis()["increase_percent"])
