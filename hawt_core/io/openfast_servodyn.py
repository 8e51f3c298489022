"""ServoDyn and the drivetrain of an OpenFAST deck (io/openfast.py's reader passes its deck):
the yaw spring and damper, ElastoDyn's DrTrDOF and GenDOF, and the generator torque law
OpenFAST's linearization keeps (ServoDyn's simple variable-speed control)."""
from __future__ import annotations

import math
from pathlib import Path

from ..model import Drivetrain
from .turbine_yaml import TurbineFileError

__all__ = ["servodyn_keys", "yaw_spring", "drivetrain", "simple_vs_slope"]


def servodyn_keys(deck, comp: dict) -> dict | None:
    """The deck's ServoDyn keys (None without ServoDyn, or when it cannot be read: warned)."""
    if not comp["CompServo"]:
        return None
    try:
        sd = deck.path(deck.fst.parent, deck.vt["Fst"]["ServoFile"], "ServoDyn")
        deck.read_keys("ServoDyn", sd, lambda kf: deck.vt.__setitem__("ServoDyn",
                                                                       dict(kf.values)))
    except TurbineFileError as exc:
        deck.warnings.append(f"ServoDyn not read ({exc}); the yaw spring and damper are 0 "
                             "and no generator-torque controller is assumed")
        return None
    deck.warnings.append(f"{sd.name}: the pitch, torque and yaw controllers are not "
                         "modelled (fixed pitch; a free generator's torque is trimmed by the "
                         "steady state, with the slope of ServoDyn's simple variable-speed "
                         "law when VSContrl = 1)")
    return deck.vt["ServoDyn"]


def yaw_spring(deck, servo: dict | None) -> tuple:
    if servo is None:
        return 0.0, 0.0
    k = deck.number("ServoDyn", "YawSpr", rule=">= 0")
    c = deck.number("ServoDyn", "YawDamp", rule=">= 0")
    deck.notes.append(f"yaw bearing: spring {k:.6g} N m/rad and damper {c:.6g} N m s/rad "
                      "from ServoDyn (YawSpr, YawDamp)")
    return k, c


def drivetrain(deck, ed_file: Path, servo: dict | None):
    """ElastoDyn's DrTrDOF (shaft torsion, DTTorSpr/DTTorDmp) and GenDOF (a free generator,
    GenIner x GBRatio^2 on the low-speed shaft) -> a hawt Drivetrain (None: both off, the
    rotor turns at RotSpeed)."""
    twist = deck.flag("ElastoDyn", "DrTrDOF")
    free = deck.flag("ElastoDyn", "GenDOF")
    if not (twist or free):
        return None
    ratio = deck.number("ElastoDyn", "GBRatio", rule="> 0")
    if deck.number("ElastoDyn", "GBoxEff", rule="> 0") != 100.0:
        deck.warnings.append(f"{ed_file.name}: GBoxEff = {deck.vt['ElastoDyn']['GBoxEff']} "
                             "read but not modelled (an ideal gearbox)")
    torque = servo.get("VSContrl") if servo is not None else 0
    slope = 0.0
    if free and torque == 1:
        # ServoDyn's simple variable-speed law, as OpenFAST linearizes it: the steady state
        # trims a constant offset (CalcSteady, TrimCase 2), the law's slope stays
        slope, region = simple_vs_slope(deck, ratio)
        deck.notes.append(f"drivetrain: a free generator under ServoDyn's simple variable-speed "
                          f"law (VSContrl = 1): its torque trimmed by the steady state, the "
                          f"law's slope at RotSpeed ({region}) {slope:.6g} N m s/rad (HSS) "
                          "kept (generator_torque_slope)")
    elif free and torque:
        # the generator torque comes from a controller hawt does not model (yet): a
        # speed-regulated generator is closer to it than a torque-free one (no steady state
        # under gravity with a free rotor)
        free = False
        deck.warnings.append(
            f"{ed_file.name}: GenDOF = True with a generator-torque controller (ServoDyn "
            f"VSContrl = {torque}), which is not modelled: hawt holds the generator at the rotor "
            "speed (drivetrain.generator: prescribed)")
    if free and not slope:
        deck.notes.append("drivetrain: a free generator (GenDOF = True, no generator torque "
                          "controller) -- a zero-frequency rotation mode")
    if not (twist or free):
        return None                          # a rigid shaft at the held speed: the default
    return Drivetrain(stiffness=deck.number("ElastoDyn", "DTTorSpr", rule="> 0") if twist
                      else None,
                      damping=deck.number("ElastoDyn", "DTTorDmp", rule=">= 0") if twist
                      else 0.0,
                      generator_inertia=deck.number("ElastoDyn", "GenIner", rule=">= 0"),
                      gearbox_ratio=ratio, generator="free" if free else "prescribed",
                      generator_torque_slope=slope)


def simple_vs_slope(deck, ratio: float) -> tuple:
    """(dT/d(omega_g) [N m s/rad, HSS], region) of ServoDyn's simple variable-speed law at
    the generator speed RotSpeed x GBRatio: region 2, T = VS_Rgn2K omega^2 (slope 2 VS_Rgn2K
    omega) below the transition speed; region 2 1/2, the induction-generator line of slope
    VS_RtTq / (VS_RtGnSp - VS_SySp), VS_SySp = VS_RtGnSp / (1 + VS_SlPc/100); region 3
    (at or above VS_RtGnSp), constant torque, 0.  ServoDyn's input units: rpm, N m/rpm^2."""
    rpm_si = math.pi / 30.0
    k = deck.number("ServoDyn", "VS_Rgn2K", rule=">= 0") / rpm_si ** 2
    rated = deck.number("ServoDyn", "VS_RtGnSp", rule="> 0") * rpm_si
    rated_torque = deck.number("ServoDyn", "VS_RtTq", rule=">= 0")
    slip = deck.number("ServoDyn", "VS_SlPc", rule=">= 0") / 100.0
    speed = deck.number("ElastoDyn", "RotSpeed") * rpm_si * ratio
    sync = rated / (1.0 + slip)
    if slip <= 0:
        line, transition = 0.0, rated
    else:
        line = rated_torque / (rated - sync)
        transition = (sync if k == 0 else
                      (line - math.sqrt(line * (line - 4.0 * k * sync))) / (2.0 * k))
    if speed >= rated:
        return 0.0, "region 3"
    if speed < transition:
        return 2.0 * k * speed, "region 2"
    return line, "region 2 1/2"
