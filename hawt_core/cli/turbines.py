"""``hawt turbines`` (the shipped turbines) and ``hawt import`` (an OpenFAST deck, a HAWC2
model or a WindIO file -> a hawt turbine file)."""

from __future__ import annotations

import sys
from pathlib import Path

from .parser import command


@command("turbines", help="list the turbines shipped with hawt (short names for TURBINE)",
         description="The turbines shipped with hawt: each short name can be given wherever "
                     "a command takes TURBINE (hawt modes nrel5mw).")
def cmd_turbines(args) -> int:
    from ..io.catalog import shipped_turbines
    rows = shipped_turbines()
    if args.json:
        import json
        print(json.dumps(rows, indent=1))
        return 0
    print(f"{'name':12s} {'blades':>6s} {'radius m':>9s} {'rpm':>6s}  {'tower':20s} description")
    for r in rows:
        print(f"{r['name']:12s} {r['blades']:6d} {r['rotor_radius_m']:9.2f} "
              f"{r['rotor_speed'] * 30 / 3.141592653589793:6.2f}  {r['tower']:20s} "
              f"{r['description']}")
    return 0


@cmd_turbines.arguments
def _turbines_args(p):
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


@command("import", help="convert an OpenFAST deck, a HAWC2 model or a WindIO file into a "
                        "hawt turbine file",
         description="Read an OpenFAST deck (.fst with its ElastoDyn, BeamDyn, ServoDyn, AeroDyn "
                     "files; any OpenFAST version: read by its keys), a HAWC2 model (.htc with "
                     "its st, ae, pc files and HAWCStab2 operational data), or a WindIO turbine "
                     "file with windio (validated against its schema first), and write the "
                     "hawt turbine file (YAML). What "
                     "is read but not modelled is printed as a warning and kept in the file's "
                     "header.")
def cmd_import(args) -> int:
    from ..io import dump_turbine
    from dataclasses import replace
    if args.operation is not None and args.format != "hawc2":
        raise ValueError("--operation: only for 'hawt import hawc2' (HAWCStab2 operational "
                         "data)")
    if args.format == "openfast":
        from ..io.openfast import read_openfast as read
    elif args.format == "hawc2":
        from ..io.hawc2_turbine import read_hawc2

        def read(path):
            return read_hawc2(path, operation=args.operation)
    else:
        from ..io.windio import read_windio as read
    result = read(args.path)
    turbine = result.turbine
    if args.name:
        turbine = replace(turbine, name=args.name)
    header = (f"turbine: {args.description}\n" if args.description else "") + result.header()
    text = dump_turbine(turbine, header=header)
    for n in result.notes:
        print(f"hawt: note: {n}", file=sys.stderr)
    for w in result.warnings:
        print(f"hawt: warning: {w}", file=sys.stderr)
    if args.output in (None, "-"):
        sys.stdout.write(text)
    else:
        Path(args.output).write_text(text, encoding="utf-8")
        print(f"wrote {args.output}", file=sys.stderr)
    return 0


@cmd_import.arguments
def _import_args(p):
    p.add_argument("format", choices=("openfast", "hawc2", "windio"), help="the input format")
    p.add_argument("path", metavar="PATH",
                   help="the deck's main file (.fst), the HAWC2 model's main file (.htc) or "
                        "the WindIO turbine file (.yaml)")
    p.add_argument("--operation", metavar="FILE", default=None,
                   help="hawc2: HAWCStab2 operational data (.opt, operation.dat) giving the "
                        "rotor speed and pitch (default: the hawcstab2 block's, or the one "
                        ".opt or operation.dat in the model's data folder)")
    p.add_argument("-o", "--output", metavar="FILE.yaml", default=None,
                   help="write the hawt turbine file here (default: standard output)")
    p.add_argument("--name", default=None, help="turbine name (default: the input's file name)")
    p.add_argument("--description", default=None,
                   help="one line saying what the turbine is (kept in the header)")
