"""The aerodynamic subcommands of ``hawt``: ``aero-table`` (rigid-rotor Cp, Ct, Cq surfaces)."""

from __future__ import annotations

import argparse

from .parser import command, finite_float, load, turbine_arg

#: Most points of one grid axis.
MAX_GRID = 500


def grid_type(name: str, low: float, high: float, unit: str, integer_count: bool = True):
    """argparse type: START:STOP:COUNT -> COUNT evenly spaced values from START to STOP
    (low <= START <= STOP <= high; COUNT 1 to MAX_GRID, START = STOP when COUNT is 1)."""
    allowed = (f"need START:STOP:COUNT with {low:g} <= START <= STOP <= {high:g} [{unit}] and "
               f"COUNT from 1 to {MAX_GRID}")

    def conv(text: str):
        parts = text.split(":")
        if len(parts) == 1:
            parts = [parts[0], parts[0], "1"]
        if len(parts) != 3:
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}")
        try:
            start, stop = (finite_float(name, unit=unit)(p) for p in parts[:2])
            count = int(parts[2])
        except (argparse.ArgumentTypeError, ValueError):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}") from None
        if not (low <= start <= stop <= high and 1 <= count <= MAX_GRID) \
                or (count > 1 and stop == start) or (count == 1 and stop != start):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; {allowed}")
        if count == 1:
            return [start]
        return [start + (stop - start) * i / (count - 1) for i in range(count)]
    return conv


@command("aero-table", help="rigid-rotor Cp, Ct, Cq against tip-speed ratio and pitch (BEM)",
         description="Steady blade-element momentum theory (Ning 2014; Prandtl tip and hub "
                     "loss, Buhl's high-induction correction) of the rigid rotor over a grid "
                     "of tip-speed ratios and collective pitch angles: the power, thrust and "
                     "torque coefficient surfaces controller tools consume. Prints the "
                     "optimum, JSON with --json, ROSCO's Cp_Ct_Cq file with --rosco.")
def cmd_aero_table(args) -> int:
    from ..analyses.aero_table import aero_table
    turbine = load(args.turbine)
    table = aero_table(turbine, args.tsr, args.pitch, wind_speed=args.wind_speed,
                       tip_loss=not args.no_tip_loss, hub_loss=not args.no_hub_loss,
                       drag_in_induction=not args.no_drag_in_induction)
    if args.rosco:
        table.save_rosco(args.rosco)
    if args.plot:
        table.plot(args.plot)
    if args.json:
        print(table.to_json(indent=None))
        return 0
    opt = table.optimum()
    print(f"{turbine.name}: {len(table.tsr)} tip-speed ratios x {len(table.pitch_deg)} pitch "
          f"angles ({table.settings['stations']} blade stations)")
    print(f"maximum Cp {opt['cp']:.4f} at tip-speed ratio {opt['tsr']:.4g}, pitch "
          f"{opt['pitch_deg']:.4g} deg (Ct {opt['ct']:.4f})")
    for what, path in (("ROSCO table", args.rosco), ("picture", args.plot)):
        if path:
            print(f"{what} written to {path}")
    return 0


@cmd_aero_table.arguments
def _aero_table_args(p):
    from ..analyses.aero_table import MAX_TSR, PITCH_RANGE_DEG
    turbine_arg(p)
    p.add_argument("--tsr", type=grid_type("--tsr", 1e-3, MAX_TSR, "-"), default="2:14:25",
                   metavar="START:STOP:COUNT", help="tip-speed ratios (default 2:14:25)")
    p.add_argument("--pitch", type=grid_type("--pitch", *PITCH_RANGE_DEG, "deg"),
                   default="-5:25:31", metavar="START:STOP:COUNT",
                   help="collective pitch angles [deg, towards feather] (default -5:25:31; "
                        "a negative start needs the = form: --pitch=-5:25:31)")
    p.add_argument("--wind-speed", type=finite_float("--wind-speed", minimum=0.1,
                                                     unit="m/s"),
                   default=10.0, metavar="U", help="wind speed [m/s] (default 10; the "
                   "coefficients do not depend on it)")
    p.add_argument("--no-tip-loss", action="store_true", help="no Prandtl tip loss")
    p.add_argument("--no-hub-loss", action="store_true", help="no Prandtl hub loss")
    p.add_argument("--no-drag-in-induction", action="store_true",
                   help="leave the drag out of the induction equations (AeroDyn's "
                        "AIDrag/TIDrag = False)")
    p.add_argument("--json", action="store_true",
                   help='print {"tsr", "pitch_deg", "cp", "ct", "cq" ([tsr][pitch]), ...}')
    p.add_argument("--rosco", metavar="FILE", default=None,
                   help="write ROSCO's Cp_Ct_Cq text file")
    p.add_argument("--plot", metavar="FILE.png", default=None,
                   help="write Cp and Ct contours to this PNG file")
