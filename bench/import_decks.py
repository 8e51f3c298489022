"""Import time of every OpenFAST deck and HAWC2 model hawt is tried on (issue 35: each < 2 s),
and what each brings: the warnings and the files read.

Decks: the rosco wheel's (v5 layout; every Test_Cases deck with an .fst) and the older
layouts committed in tests/data/openfast (openfast_toolbox's NREL 5-MW v3.2 and v3.x decks,
the IEA 15-MW reference turbine's own v3.5-v4 deck); the HAWC2 models in tests/data/hawc2
(h2lib_tests' DTU 10-MW and IEA 15-MW onshore).  Each import is timed in this process,
best of three (the first pays the imports of numpy and friends once).

    PYTHONPATH=. .venv/bin/python bench/import_decks.py
"""
from __future__ import annotations

import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def decks() -> list:
    from hawt_core.io.catalog import rosco_test_cases
    out = sorted((ROOT / "tests" / "data" / "openfast").rglob("*.fst"))
    cases = rosco_test_cases()
    if cases is not None:
        out += sorted(cases.rglob("*.fst"))
    hawc2 = ROOT / "tests" / "data" / "hawc2"
    out += [hawc2 / "DTU_10_MW" / "htc" / "DTU_10MW_RWT.htc",
            hawc2 / "IEA-15-240-RWT-Onshore" / "htc" / "IEA_15MW_RWT_Onshore.htc"]
    return out


def main() -> None:
    from hawt_core.io import TurbineFileError
    from hawt_core.io.hawc2_turbine import read_hawc2
    from hawt_core.io.openfast import read_openfast
    print(f"{'deck':<70}{'best [s]':>10}{'warnings':>10}{'files':>7}  result")
    worst = 0.0
    for fst in decks():
        times, result = [], None
        for _ in range(3):
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    read = read_hawc2 if fst.suffix == ".htc" else read_openfast
                    result = read(fst)
                status = "ok"
            except TurbineFileError as exc:
                status = "refused: " + " ".join(str(exc).split())[:90]
            times.append(time.perf_counter() - t0)
        best = min(times)
        worst = max(worst, best)
        name = str(fst.relative_to(ROOT) if fst.is_relative_to(ROOT) else fst)
        name = name.replace(".venv/lib/python3.11/site-packages/", "")
        nw = len(result.warnings) if status == "ok" else 0
        nf = len(result.sources) if status == "ok" else 0
        print(f"{name[-70:]:<70}{best:>10.3f}{nw:>10d}{nf:>7d}  {status}")
    print(f"slowest import: {worst:.3f} s (target < 2 s)")


if __name__ == "__main__":
    main()
