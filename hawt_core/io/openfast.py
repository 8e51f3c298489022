"""OpenFAST decks -> hawt turbines, every file read by its keys (io/openfast_keys.py), so
that decks of any OpenFAST version in use (v2.x to v5, and FAST v8 ones) come in.

What is read (all files relative to the ``.fst``):

- ElastoDyn main file: rotor (blade count, precone, rotor speed), hub (radius, mass, inertia),
  nacelle (overhang, shaft tilt, tower-top-to-shaft height, mass, mass centre, yaw inertia,
  yaw bearing mass), degrees of freedom, tower height;
- ElastoDyn blade file: mass density, flap and edge stiffness, structural twist (with the
  adjustment factors AdjBlMs, AdjFlSt, AdjEdSt applied, as ElastoDyn does);
- ElastoDyn tower file: mass density, fore-aft and side-side stiffness (AdjTwMa, AdjFASt,
  AdjSSSt applied);
- BeamDyn blade file (when the deck names one): the full 6x6 stiffness and mass matrices.
  With ``CompElast = 2`` (BeamDyn blades) they are the blade; with ``CompElast = 1`` the
  ElastoDyn blade is the blade (inextensible and shear-rigid, as ElastoDyn's) and the BeamDyn
  file of the same deck supplies what an ElastoDyn blade lacks (torsional rigidity, section
  rotary inertia);
- ServoDyn (io/openfast_servodyn.py): the yaw spring and damper (YawSpr, YawDamp) that hold
  the yaw DOF, and with GenDOF the simple variable-speed law's slope (VSContrl = 1).

Frames and signs (hawt_core.model): hawt's nacelle frame is (y1 up, y2 lateral, y3 downwind),
ElastoDyn's (xn downwind, yn lateral to the left looking downwind, zn up), so a point
(xn, yn, zn) is (zn, -yn, xn) in hawt.  ``OverHang`` (negative upwind) is hawt's
``yaw_to_teeter``; ``ShftTilt`` and ``PreCone`` keep their sign (negative tilt raises an
upwind rotor, negative precone cones it upwind).  BeamDyn's section frame (x flapwise towards
the tower, y towards the trailing edge, z along the span; the IEC blade frame) is
(b3, -b2, b1) in hawt's blade frame (b1 span, b2 towards the leading edge = the direction of
motion, b3 flapwise downwind).  ElastoDyn's StrcTwst and BeamDyn's initial twist are positive
towards feather (leading edge upwind), i.e. from b2 towards -b3: hawt's twist is minus them.

What hawt cannot honour is refused with the file and the key (modal stiffness tuners other
than 1, a blade mode switched off, a platform DOF, blade pitch DOF, three different blades);
what is read but not modelled is reported in :attr:`ImportResult.warnings` (mode-shape
polynomials, structural damping, the drivetrain, substructures, ...), never dropped silently.
"""
from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..model import (Beam, BeamDamping, Gravity, Hub, Nacelle, Rotor, SectionTable,
                     Turbine)
from .imported import (ELEMENTS, IEC_TO_HAWT, BladeAxis, ImportResult, hub_yaw_share,
                       iec_axes_to_hawt, interp_stations, package_version,
                       sections_from_matrices, untwist_sections)
from .openfast_keys import (KeyedFile, KeyedFileError, aerodyn_files, beamdyn_blade,
                            beamdyn_main, read_keyed)
from .openfast_servodyn import drivetrain, servodyn_keys, yaw_spring
from .turbine_yaml import TurbineFileError

__all__ = ["ImportResult", "read_openfast", "IMPORTER", "ELEMENTS", "TOWER_STEEL"]

#: Importer name and version written into the header of converted files.
IMPORTER = f"hawt {package_version('hawt')} OpenFAST importer (key-based, any version)"

#: Steel-tube assumptions for what an ElastoDyn tower file lacks (torsional rigidity and
#: section rotary inertia): G/E of steel and E / rho [m^2/s^2] with ElastoDyn's effective
#: tower density (NREL 5-MW: 8500 kg/m^3, E = 210 GPa).  For a thin tube GJ = 2 G I and the
#: rotary inertia per length about a diameter is rho I = rho EI / E.
TOWER_STEEL = {"G_over_E": 80.8 / 210.0, "E_over_rho": 210e9 / 8500.0}

#: Role of the deck's main file (.fst) in ``ImportResult.sources`` and the messages.
MAIN = "OpenFAST main"


#: Keys that older OpenFAST layouts lack, with the value that reproduces what those versions
#: did (module -> key -> (value, why)).
LATER_KEYS = {
    "ElastoDyn": {
        "PitchDOF": (False, "no blade-pitch DOF before it existed (OpenFAST v4)"),
        **{f"BlPIner({k})": (0.0, "no pitch-bearing inertia before it existed")
           for k in (1, 2, 3)},
        **{f"PBrIner({k})": (0.0, "no pitch-bearing inertia before it existed")
           for k in (1, 2, 3)},
    },
}


class _Deck:
    """One deck being read: the reader, its files, and the problems found so far."""

    def __init__(self, fst: Path):
        self.fst = fst
        #: per module, its keys' values (the dictionaries openfast-io's readers fill, and
        #: under the same names: the importer was written against them)
        self.vt: dict = {}
        self.warnings: list = []
        self.notes: list = []
        self.sources: dict = {}
        self.keys: dict = {}

    def path(self, base: Path, name: str, role: str) -> Path:
        name = str(name).strip().strip('"').strip("'")
        p = Path(name) if os.path.isabs(name) else base / name
        p = Path(os.path.normpath(p))
        if not p.is_file():
            raise TurbineFileError(str(base if role == "ElastoDyn" else self.sources.get(
                "ElastoDyn", self.fst)), [f"{role} file {name!r} not found (looked for {p})"])
        return p

    def read_keys(self, what: str, path: Path, fill) -> KeyedFile:
        """Read ``path`` by its keys (io/openfast_keys.py: any OpenFAST version's layout) and
        ``fill(keyed_file)`` the reader's dictionaries; a table that does not hold ->
        TurbineFileError naming the file and line."""
        self.sources[what] = str(path)
        try:
            kf = read_keyed(path)
            fill(kf)
        except KeyedFileError as exc:
            # the file the reader was in: the one named, or one it leads to (a polar, a blade)
            raise TurbineFileError(exc.file, [exc.message
                                              + (f" (line {exc.line})" if exc.line else "")
                                              + f"; check it against the {what} input format"])
        self.keys[what] = {k: (kf.lines[k], kf.values[k]) for k in kf.values}
        return kf

    def _default(self, module: str, key: str, src: dict):
        """The value of a key older OpenFAST layouts lack (LATER_KEYS), warned once; None
        for any other missing key."""
        if key in src or key not in LATER_KEYS.get(module, {}):
            return src.get(key)
        value, why = LATER_KEYS[module][key]
        src[key] = value
        self.warnings.append(f"{Path(self.sources.get(module, str(self.fst))).name}: {key} "
                             f"missing (an older OpenFAST layout): taken as {value!r}, {why}")
        return value

    def number(self, module: str, key: str, *, rule: str = "finite", allowed: str = "",
               vt: dict | None = None) -> float:
        src = self.vt[module] if vt is None else vt
        value = self._default(module, key, src)
        file = self.sources.get(module, str(self.fst))
        line = self.keys.get(module, {}).get(key, (None, None))[0]
        at = f" (line {line})" if line else ""
        if value is None:
            raise TurbineFileError(file, [f"{key}: required key is missing"])
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise TurbineFileError(file, [f"{key}{at} = {value!r}: must be a number"
                                          + (f" ({allowed})" if allowed else "")]) from None
        ok = {"finite": math.isfinite(x), "> 0": x > 0, ">= 0": x >= 0,
              "== 1": x == 1.0}[rule] and math.isfinite(x)
        if not ok:
            raise TurbineFileError(file, [f"{key}{at} = {value!r}: "
                                          + (allowed or f"must be {rule}")])
        return x

    def flag(self, module: str, key: str) -> bool:
        value = self._default(module, key, self.vt[module])
        if not isinstance(value, bool):
            raise TurbineFileError(self.sources.get(module, str(self.fst)),
                                   [f"{key} = {value!r}: must be True or False"])
        return value


def _table(deck: _Deck, module: str, keys: tuple, vt: dict) -> dict:
    """Distributed properties as float arrays, checked finite, stations increasing 0..1."""
    file = deck.sources[module]
    out = {}
    for k in keys:
        try:
            out[k] = np.array(vt[k], dtype=float)
        except (KeyError, TypeError, ValueError):
            raise TurbineFileError(file, [f"{k}: the distributed-property column is missing "
                                          "or not numeric"]) from None
        if not np.all(np.isfinite(out[k])):
            raise TurbineFileError(file, [f"{k}: every value must be a finite number"])
    st = out[keys[0]]
    if len(st) < 2 or st[0] != 0.0 or st[-1] != 1.0 or np.any(np.diff(st) <= 0):
        raise TurbineFileError(file, [f"{keys[0]} = {st.tolist()}: must increase strictly "
                                      "from 0 to 1 (at least two stations)"])
    for k in keys[1:]:
        if k not in ("StrcTwst",) and np.any(out[k] <= 0):
            raise TurbineFileError(file, [f"{k}: every value must be > 0"])
    return out


def _main(deck: _Deck):
    # by its keys: every OpenFAST version's main file (openfast-io reads the v5 layout only)
    deck.read_keys(MAIN, deck.fst, lambda kf: deck.vt.__setitem__("Fst", dict(kf.values)))
    fst = deck.vt[MAIN] = deck.vt["Fst"]           # the main file's keys under its role
    comp = {k: fst.get(k) for k in ("CompElast", "CompAero", "CompServo", "CompHydro",
                                    "CompSub", "CompMooring", "CompIce", "CompInflow")}
    if comp["CompElast"] not in (1, 2):
        raise TurbineFileError(str(deck.fst), [
            f"CompElast = {comp['CompElast']!r}: hawt reads ElastoDyn (1) or ElastoDyn + "
            "BeamDyn blades (2); SimplifiedElastoDyn (3) has no flexible structure"])
    for k in ("CompHydro", "CompSub", "CompMooring", "CompIce"):
        if comp[k]:
            deck.warnings.append(f"{deck.fst.name}: {k} = {comp[k]} read but not modelled: "
                                 "hawt clamps the tower at its base (no substructure, "
                                 "hydrodynamics, mooring or ice)")
    if comp["CompAero"] not in (0, 2):
        deck.warnings.append(f"{deck.fst.name}: CompAero = {comp['CompAero']} (AeroDisk): "
                             "read but not imported; hawt reads AeroDyn (CompAero = 2)")
    return comp


#: AeroDyn options hawt reads but does not take: its own models are chosen by flags
#: (--inflow, --airfoil); warned when set.
AERODYN_OPTIONS = ("TwrPotent", "TwrShadow", "UA_Mod", "DBEMT_Mod", "SkewMomCorr")
#: AeroDyn options whose setting hawt always has (BEM with induction, Prandtl's tip and hub
#: losses, tangential induction, drag in both induction equations); warned when different.
AERODYN_FIXED = {"Wake_Mod": 1, "TipLoss": True, "HubLoss": True, "TanInd": True,
                 "AIDrag": True, "TIDrag": True}


def _tower_aerodynamics(deck: _Deck, tower):
    """AeroDyn's tower table (TwrElev, TwrDiam, TwrCd) as model.TowerAerodynamics when
    TwrAero = True and the tower is flexible, else None (with a note)."""
    from ..model import TowerAerodynamics

    ad = deck.vt.get("AeroDyn") or {}
    if "AeroDyn" not in deck.sources or not ad.get("TwrAero"):
        return None
    adn = Path(deck.sources["AeroDyn"]).name
    if tower is None:
        deck.notes.append(f"{adn}: TwrAero = True on a rigid tower: the tower drag loads "
                          "nothing and is not kept")
        return None
    base = deck.number("ElastoDyn", "TowerBsHt")
    elev = np.asarray(ad.get("TwrElev") or [], float)
    s = (elev - base) / tower.length
    diam, cd = (np.asarray(ad.get(k) or [], float) for k in ("TwrDiam", "TwrCd"))
    problems = []
    if elev.size < 2 or diam.size != elev.size or cd.size != elev.size:
        problems.append(f"NumTwrNds = {ad.get('NumTwrNds')!r}: TwrAero = True needs a tower "
                        "table of at least 2 rows (TwrElev, TwrDiam, TwrCd)")
    elif np.any(np.diff(s) <= 0) or s[0] < -1e-6 or s[-1] > 1 + 1e-6:
        problems.append(f"TwrElev = {elev.tolist()}: must increase strictly within the tower, "
                        f"TowerBsHt = {base:g} to TowerHt = {base + tower.length:g} m")
    elif np.any(diam <= 0) or np.any(cd < 0):
        problems.append(f"TwrDiam = {diam.tolist()}, TwrCd = {cd.tolist()}: allowed TwrDiam "
                        "> 0 and TwrCd >= 0")
    if problems:
        raise TurbineFileError(deck.sources["AeroDyn"], problems)
    # the table may stop short of the tower's ends: the end rows hold beyond
    s = np.clip(s, 0.0, 1.0)
    if s[0] > 0:
        s, diam, cd = np.r_[0.0, s], np.r_[diam[0], diam], np.r_[cd[0], cd]
    if s[-1] < 1:
        s, diam, cd = np.r_[s, 1.0], np.r_[diam, diam[-1]], np.r_[cd, cd[-1]]
    deck.notes.append(f"tower aerodynamics: drag of {elev.size} AeroDyn tower nodes (TwrAero; "
                      f"TwrDiam {diam.min():g} to {diam.max():g} m, TwrCd {cd.min():g} to "
                      f"{cd.max():g}), kept in the model")
    return TowerAerodynamics(stations=s, diameter=diam, drag=cd)


def _skew_factor(deck: _Deck, ad: dict, adn: str) -> float:
    """The Pitt/Peters skewed-wake constant from AeroDyn's skew options: Skew_Mod = 1 with
    SkewRedistr_Mod = 1 (or "default") takes SkewRedistrFactor ("default": 15 pi / 32);
    Skew_Mod 0 or -1, or SkewRedistr_Mod 0: no correction (0).  A deck without the
    options (an older AeroDyn) gets the default, with a note."""
    from ..model import PITT_PETERS_SKEW

    mode, redistr = ad.get("Skew_Mod"), ad.get("SkewRedistr_Mod")
    if mode is None:
        deck.notes.append(f"{adn}: no Skew_Mod: Pitt/Peters skewed-wake correction with "
                          "K = 15 pi / 32 (AeroDyn's default)")
        return PITT_PETERS_SKEW
    if str(redistr).strip('"').lower() == "default":
        redistr = 1
    if mode not in (-1, 0, 1) or redistr not in (0, 1):
        raise TurbineFileError(deck.sources["AeroDyn"], [
            f"Skew_Mod = {mode!r}, SkewRedistr_Mod = {redistr!r}: allowed Skew_Mod -1, 0 or 1 "
            "and SkewRedistr_Mod 0, 1 or default"])
    if mode != 1 or redistr == 0:
        return 0.0
    factor = ad.get("SkewRedistrFactor")
    if factor is None or str(factor).strip('"').lower() == "default":
        return PITT_PETERS_SKEW
    if not (isinstance(factor, (int, float)) and math.isfinite(factor) and factor >= 0):
        raise TurbineFileError(deck.sources["AeroDyn"], [
            f"SkewRedistrFactor = {factor!r}: allowed a number >= 0 or default"])
    return float(factor)


def _fill_aerodyn(deck: _Deck, kf: KeyedFile) -> None:
    """AeroDyn read by its keys (openfast_keys.aerodyn_files) into the deck's dictionaries."""
    deck.vt["AeroDyn"], deck.vt["AeroDynBlade"] = aerodyn_files(kf)


def _aerodynamics(deck: _Deck, comp: dict, nb: int, length: float):
    """The AeroDyn blade and airfoil polars (CompAero = 2) as model.Aerodynamics, or None.
    A deck whose AeroDyn files cannot be read still gives its structure: a warning names
    the file and says the aerodynamics are not imported."""
    from ..model import Aerodynamics, Polar

    if comp["CompAero"] != 2:
        return None
    try:
        ad_file = deck.path(deck.fst.parent, deck.vt["Fst"]["AeroFile"], "AeroDyn")
        deck.read_keys("AeroDyn", ad_file, lambda kf: _fill_aerodyn(deck, kf))
    except TurbineFileError as exc:
        deck.warnings.append(f"the aerodynamics are not imported: {exc}")
        return None
    ad, bl = deck.vt["AeroDyn"], deck.vt["AeroDynBlade"]
    adn = Path(deck.sources["AeroDyn"]).name
    # the blade file is relative to the AeroDyn file's folder (aerodyn_files read it there)
    base = Path(deck.sources["AeroDyn"]).parent
    names = [ad.get(f"ADBlFile{k}") for k in range(1, nb + 1)]
    if len(set(names)) > 1:
        raise TurbineFileError(deck.sources["AeroDyn"], [
            f"ADBlFile(1..{nb}) = {names}: hawt's blades are identical; allowed: one AeroDyn "
            "blade file for every blade"])
    deck.sources["AeroDyn blade"] = os.path.normpath(base / names[0])
    blade_file = deck.sources["AeroDyn blade"]
    t = _table(deck, "AeroDyn blade", ("BlSpn", "BlChord"), dict(
        BlSpn=np.asarray(bl["BlSpn"], float) / float(bl["BlSpn"][-1]), BlChord=bl["BlChord"]))
    span = float(bl["BlSpn"][-1])
    if abs(span - length) > 1e-3 * length:
        deck.warnings.append(f"{Path(blade_file).name}: BlSpn ends at {span:.6g} m but the "
                             f"structural blade is {length:.6g} m long; the aerodynamic "
                             "stations are taken as fractions of BlSpn's span")
    extra = {}
    for key, hawt, scale in (("BlCrvAC", "ac_prebend", 1.0), ("BlSwpAC", "ac_sweep", -1.0),
                             ("BlCrvAng", "cant", math.pi / 180)):
        v = scale * np.asarray(bl[key], float)
        extra[hawt] = v if np.any(v != 0) else None
    for key in ("BlCb", "BlCenBn", "BlCenBt", "BlCpn", "BlCpt", "BlCan", "BlCat", "BlCam"):
        v = bl.get(key)
        if v is not None and np.any(np.asarray(v, float) != 0):
            deck.warnings.append(f"{Path(blade_file).name}: {key} (marine hydrodynamic "
                                 "coefficients) read but not modelled")
    ids = np.asarray(bl["BlAFID"], int) - 1
    if np.any(ids < 0) or np.any(ids >= len(ad["af_data"])):
        raise TurbineFileError(blade_file, [f"BlAFID = {(ids + 1).tolist()}: must be 1 .. "
                                            f"NumAFfiles = {len(ad['af_data'])}"])
    deck.sources["AeroDyn airfoils"] = os.path.commonpath(ad["AFNames"]) \
        if len(ad["AFNames"]) > 1 else ad["AFNames"][0]
    polars, extra_tables, ua = [], [], []
    for name, tables in zip(ad["AFNames"], ad["af_data"]):
        tab = tables[0]
        if len(tables) > 1:
            extra_tables.append(Path(name).name)
        if tab.get("InclUAdata"):
            ua.append(Path(name).name)
        cm = tab["Cm"] if ad.get("InCol_Cm", 0) > 0 else [0.0] * len(tab["Alpha"])
        polars.append(Polar(name=Path(name).stem, alpha=np.radians(np.asarray(tab["Alpha"],
                                                                               float)),
                            cl=tab["Cl"], cd=tab["Cd"], cm=cm,
                            reynolds=float(tab["Re"]) if tab.get("Re") else None,
                            thickness=tab.get("RelThickness")))
    if ad.get("InCol_Cm", 0) <= 0:
        deck.warnings.append(f"{adn}: InCol_Cm = 0: the polars have no moment column; cm "
                             "taken as 0")
    if extra_tables:
        deck.warnings.append(f"{adn}: airfoils with tables at several Reynolds numbers "
                             f"({', '.join(extra_tables)}): the first table is kept")
    if ua:
        deck.warnings.append(f"{adn}: the unsteady-aerodynamics coefficients (InclUAdata) of "
                             f"{len(ua)} airfoils read but not kept: hawt's unsteady airfoil "
                             "(--airfoil jones) is attached flow, without dynamic stall")
    extra["skew_factor"] = _skew_factor(deck, ad, adn)
    given = [f"{k} = {ad[k]}" for k in AERODYN_OPTIONS if ad.get(k) not in (None, 0, False)]
    given += [f"{k} = {ad[k]}" for k, v in AERODYN_FIXED.items()
              if ad.get(k) is not None and ad.get(k) != v]
    if given:
        deck.warnings.append(f"{adn}: {', '.join(given)} read but not taken: hawt's "
                             "aerodynamics are its own models (BEM with Prandtl's tip and hub "
                             "losses, tangential induction and drag in the inductions, frozen "
                             "wake or --inflow oye, --airfoil jones, the tower's drag from "
                             "TwrAero's table; docs/aerodynamics.md)")
    deck.notes.append(f"aerodynamics: {len(t['BlSpn'])} AeroDyn blade stations and "
                      f"{len(polars)} airfoil polars (first table each), kept in the model")
    return Aerodynamics(stations=t["BlSpn"], chord=t["BlChord"],
                        twist=-np.radians(np.asarray(bl["BlTwist"], float)), airfoil=ids,
                        polars=tuple(polars), **extra)


def _check_dofs(deck: _Deck, ed_file: str, nb: int):
    blade = [k for k in ("FlapDOF1", "FlapDOF2", "EdgeDOF") if not deck.flag("ElastoDyn", k)]
    if blade:
        raise TurbineFileError(ed_file, [
            f"{blade[0]} = False: hawt's blades are beams whose every mode is free; allowed: "
            "True (all of FlapDOF1, FlapDOF2, EdgeDOF)"])
    if deck.flag("ElastoDyn", "PitchDOF"):
        raise TurbineFileError(ed_file, ["PitchDOF = True: hawt's blades have no pitch "
                                         "bearing DOF; allowed: False"])
    platform = [k for k in (f"Ptfm{a}DOF" for a in ("Sg", "Sw", "Hv", "R", "P", "Y"))
                if deck.flag("ElastoDyn", k)]
    if platform:
        deck.warnings.append(f"{Path(ed_file).name}: {', '.join(platform)} = True read but not "
                             "modelled: hawt clamps the tower at its base (TowerBsHt)")
    tower = [deck.flag("ElastoDyn", k) for k in ("TwFADOF1", "TwFADOF2", "TwSSDOF1",
                                                  "TwSSDOF2")]
    if any(tower) and not all(tower):
        raise TurbineFileError(ed_file, [
            "TwFADOF1, TwFADOF2, TwSSDOF1, TwSSDOF2 = %s: hawt's tower is a beam with all "
            "its modes, or rigid; allowed: all True or all False" % tower])
    teeter = nb == 2 and deck.flag("ElastoDyn", "TeetDOF")
    return all(tower), teeter


def _blade_beamdyn(deck: _Deck, comp: dict, nb: int):
    """BeamDyn blade (6x6 per station, hawt frame b, untwisted) or None when there is none."""
    fst = deck.vt["Fst"]
    names = [fst.get(f"BDBldFile({k})") for k in (1, 2, 3)[:max(nb, 1)]]
    name = names[0]
    if not name or str(name).strip('"').lower() in ("unused", "none", ""):
        if comp["CompElast"] == 2:
            raise TurbineFileError(str(deck.fst), ["BDBldFile(1): CompElast = 2 needs a "
                                                   "BeamDyn blade file"])
        return None
    if len(set(names)) > 1:
        raise TurbineFileError(str(deck.fst), [
            f"BDBldFile(1..{nb}) = {names}: hawt's blades are identical; allowed: one "
            "BeamDyn file for every blade"])
    try:
        bd_main = deck.path(deck.fst.parent, name, "BeamDyn")
    except TurbineFileError:
        if comp["CompElast"] == 2:
            raise
        return None
    bd, blade = {}, {}
    deck.read_keys("BeamDyn", bd_main, lambda kf: bd.update(beamdyn_main(kf)))
    if not isinstance(bd.get("BldFile"), str):
        raise TurbineFileError(str(bd_main), [f"BldFile = {bd.get('BldFile')!r}: need the "
                                              "BeamDyn blade file's name"])
    deck.read_keys("BeamDyn blade", bd_main.parent / bd["BldFile"],
                   lambda kf: blade.update(beamdyn_blade(kf)))
    deck.sources["BeamDyn blade"] = os.path.normpath(bd_main.parent / bd["BldFile"])
    kp = np.concatenate([np.column_stack([m["kp_xr"], m["kp_yr"], m["kp_zr"],
                                          m["initial_twist"]]) for m in bd["members"]])
    length = float(kp[-1, 2] - kp[0, 2])
    if not length > 0:
        raise TurbineFileError(str(bd_main), [f"kp_zr: the key points must run outward "
                                              f"along z (got {kp[0, 2]} .. {kp[-1, 2]} m)"])
    eta = np.asarray(blade["radial_stations"], float)
    K = iec_axes_to_hawt(blade["beam_stiff"])
    M = iec_axes_to_hawt(blade["beam_inertia"])
    # BeamDyn's key-point splines are functions of kp_zr: the stations eta are read as
    # fractions of the span along z (hawt's b1), as WISDEM writes them from WindIO's grid
    # (tests/test_windio.py); the line's x, -y offsets are hawt's prebend and sweep
    axis = BladeAxis(kp[:, :3], (kp[:, 2] - kp[0, 2]) / length)
    stations, sweep, prebend = axis.stations(eta)
    # section twist at the stations from the key points (towards feather -> minus hawt's)
    twist = -np.radians(np.interp(eta, axis.parameter, kp[:, 3]))
    return dict(stations=stations, K=K, M=M, twist=twist, length=length, file=bd_main,
                curve=axis.bend, prebend=prebend, sweep=sweep, blade=blade)


def _beamdyn_damping(deck: _Deck, blade: dict) -> BeamDamping | None:
    """BeamDyn's stiffness-proportional damping (damp_type = 1: mu1..mu6 [s], per strain of
    its section frame (x, y, z), z along the span) renamed to hawt's strains; damp_type 2
    (modal, BeamDyn v3.5+) is warned, not modelled."""
    name = Path(deck.sources["BeamDyn blade"]).name
    damp = blade.get("damp_type")
    if not damp:
        return None
    if int(damp) != 1:
        deck.warnings.append(f"{name}: damp_type = {damp} (modal damping of BeamDyn's own "
                             "modes) read but not modelled: hawt takes damp_type 1 "
                             "(stiffness-proportional mu) or ElastoDyn's modal ratios")
        return None
    mu = np.array([deck.number("BeamDyn blade", f"mu{i}", rule=">= 0", vt=blade)
                   for i in range(1, 7)])
    T = np.zeros((6, 6))
    T[:3, :3] = T[3:, 3:] = np.abs(IEC_TO_HAWT)
    mu_hawt = T @ mu
    deck.notes.append(f"blade: BeamDyn's stiffness-proportional damping mu = "
                      f"{' '.join(f'{v:g}' for v in mu)} s (x, y, z order), hawt's strain "
                      f"order {' '.join(f'{v:g}' for v in mu_hawt)} s, applied in hawt's "
                      "untwisted blade frame")
    return BeamDamping(stiffness=tuple(float(v) for v in mu_hawt))


def _blade(deck: _Deck, comp: dict, ed_file: Path, nb: int, length: float) -> Beam:
    bd = _blade_beamdyn(deck, comp, nb)
    if comp["CompElast"] == 2:
        if abs(bd["length"] - length) > 1e-3 * length:
            deck.warnings.append(f"{bd['file'].name}: blade length {bd['length']:.4g} m "
                                 f"(kp_zr) differs from TipRad - HubRad = {length:.4g} m; "
                                 "the BeamDyn length is used")
        if bd["curve"] > 0:
            deck.notes.append(
                f"blade: prebend and sweep from the key points kp_xr, -kp_yr (up to "
                f"{bd['curve']:.3g} m; a curved reference line, the stations eta taken as "
                "fractions of the span along kp_zr)")
        deck.notes.append("blade: the full 6x6 stiffness and mass of the BeamDyn blade "
                          "(CompElast = 2), turned by the initial twist into hawt's blade frame")
        sec = sections_from_matrices(bd["stations"], untwist_sections(bd["K"], bd["twist"]),
                                     untwist_sections(bd["M"], bd["twist"]),
                                     prebend=bd["prebend"], sweep=bd["sweep"])
        return Beam(length=bd["length"], sections=sec,
                    damping=_beamdyn_damping(deck, bd["blade"]), **ELEMENTS["blade"])

    # ElastoDyn blade (CompElast = 1)
    fl = deck.vt["ElastoDyn"]
    names = [fl.get(f"BldFile{k}") for k in (1, 2, 3)[:nb]]
    if len(set(names)) > 1:
        raise TurbineFileError(str(ed_file), [f"BldFile1..{nb} = {names}: hawt's blades are "
                                              "identical; allowed: one blade file"])
    bfile = deck.path(ed_file.parent, names[0], "ElastoDyn blade")
    vt = {}

    def fill(kf):
        vt.update(kf.values)
        vt.update(kf.table("BlFract", "NBlInpSt"))
    deck.read_keys("ElastoDyn blade", bfile, fill)
    for k in ("FlStTunr1", "FlStTunr2"):
        deck.number("ElastoDyn blade", k, rule="== 1", vt=vt,
                    allowed="a modal stiffness tuner applies to ElastoDyn's assumed mode "
                            "shapes, which hawt's beam does not use; allowed: 1")
    adj = {k: deck.number("ElastoDyn blade", k, rule="> 0", vt=vt)
           for k in ("AdjBlMs", "AdjFlSt", "AdjEdSt")}
    t = _table(deck, "ElastoDyn blade", ("BlFract", "BMassDen", "FlpStff", "EdgStff",
                                          "StrcTwst"), vt)
    deck.warnings.append(f"{bfile.name}: BldFl1Sh, BldFl2Sh, BldEdgSh (mode-shape "
                         "polynomials) read but not used: hawt's beam elements compute the "
                         "shapes")
    damping = _modal_damping(deck, "ElastoDyn blade", vt, {
        "flap": ("BldFlDmp1", "BldFlDmp2"), "edge": ("BldEdDmp1",)})
    x = t["BlFract"]
    mass = adj["AdjBlMs"] * t["BMassDen"]
    ei2, ei3 = adj["AdjFlSt"] * t["FlpStff"], adj["AdjEdSt"] * t["EdgStff"]
    twist = -np.radians(t["StrcTwst"])
    if bd is not None:
        K = interp_stations(x, bd["stations"], bd["K"])
        M = interp_stations(x, bd["stations"], bd["M"])
        # what the two files say about the same blade (mass and mean stiffness over the span)
        m_ed, m_bd = (length * np.trapezoid(v, x) for v in (t["BMassDen"], M[:, 0, 0]))
        k_ed, k_bd = (np.trapezoid(v, x) for v in (t["FlpStff"], K[:, 4, 4]))
        M = M * adj["AdjBlMs"]
        deck.notes.append(
            f"blade: mass, flap and edge stiffness and twist from the ElastoDyn blade "
            f"{bfile.name} (CompElast = 1, AdjBlMs = {adj['AdjBlMs']:g}), inextensible and "
            f"shear-rigid as ElastoDyn's; torsional rigidity and section inertias (scaled by "
            f"AdjBlMs) from the deck's BeamDyn blade "
            f"{Path(deck.sources['BeamDyn blade']).name}, which ElastoDyn lacks "
            f"(blade mass without AdjBlMs: {m_ed:.6g} kg ElastoDyn, {m_bd:.6g} kg BeamDyn; "
            f"span-mean flap stiffness {k_ed:.4g} and {k_bd:.4g} N m^2)")
        sec = SectionTable(stations=x, mass=mass, i1=M[:, 3, 3], i2=M[:, 4, 4], i3=M[:, 5, 5],
                           gj=K[:, 3, 3], ei2=ei2, ei3=ei3, twist=twist)
    else:
        # ElastoDyn's blade is torsionally rigid with no rotary inertia: a torsion 100 times
        # stiffer than the bending and a tiny rotary inertia keep hawt's beam close to it
        gj = 100.0 * np.maximum(ei2, ei3)
        i23 = 1e-6 * mass
        deck.warnings.append(
            f"{bfile.name}: an ElastoDyn blade has no torsional rigidity or section rotary "
            "inertia and the deck names no BeamDyn blade; hawt takes GJ = 100 max(EI) and "
            "i2 = i3 = 1e-6 m^2 x mass (a torsionally rigid blade, as ElastoDyn's); give "
            "them in the hawt file if known")
        sec = SectionTable(stations=x, mass=mass, i1=2 * i23, i2=i23, i3=i23, gj=gj,
                           ei2=ei2, ei3=ei3, twist=twist)
    return Beam(length=length, sections=sec, damping=damping, **ELEMENTS["blade"])


def _tower(deck: _Deck, ed_file: Path, flexible: bool) -> Beam | None:
    ed = deck.vt["ElastoDyn"]
    if not flexible:
        deck.notes.append("tower: rigid (every tower DOF is False)")
        return None
    tfile = deck.path(ed_file.parent, ed.get("TwrFile"), "ElastoDyn tower")
    vt = {}

    def fill(kf):
        vt.update(kf.values)
        vt.update(kf.table("HtFract", "NTwInpSt"))
    deck.read_keys("ElastoDyn tower", tfile, fill)
    for k in ("FAStTunr1", "FAStTunr2", "SSStTunr1", "SSStTunr2"):
        deck.number("ElastoDyn tower", k, rule="== 1", vt=vt,
                    allowed="a modal stiffness tuner applies to ElastoDyn's assumed mode "
                            "shapes, which hawt's beam does not use; allowed: 1")
    adj = {k: deck.number("ElastoDyn tower", k, rule="> 0", vt=vt)
           for k in ("AdjTwMa", "AdjFASt", "AdjSSSt")}
    t = _table(deck, "ElastoDyn tower", ("HtFract", "TMassDen", "TwFAStif", "TwSSStif"), vt)
    height = deck.number("ElastoDyn", "TowerHt") - deck.number("ElastoDyn", "TowerBsHt")
    if not height > 0:
        raise TurbineFileError(str(ed_file), [f"TowerHt - TowerBsHt = {height}: the tower "
                                              "must have a positive height"])
    mass = adj["AdjTwMa"] * t["TMassDen"]
    ei2, ei3 = adj["AdjFASt"] * t["TwFAStif"], adj["AdjSSSt"] * t["TwSSStif"]
    ei = 0.5 * (ei2 + ei3)
    gj = 2.0 * TOWER_STEEL["G_over_E"] * ei
    i23 = ei / TOWER_STEEL["E_over_rho"]
    deck.warnings.append(
        f"{tfile.name}: TwFAM1Sh.., TwSSM1Sh.. (mode-shape polynomials) read but not used: "
        "hawt's beam elements compute the shapes")
    damping = _modal_damping(deck, "ElastoDyn tower", vt, {
        "fore_aft": ("TwrFADmp1", "TwrFADmp2"), "side_side": ("TwrSSDmp1", "TwrSSDmp2")})
    deck.warnings.append(
        f"{tfile.name}: an ElastoDyn tower has no torsional rigidity or rotary inertia; hawt "
        "takes those of a thin steel tube with the same bending rigidity (GJ = 2 G/E EI, "
        "G/E = 0.385; i2 = i3 = EI rho/E, E/rho = 210 GPa / 8500 kg/m^3); axial and shear "
        "rigid as in ElastoDyn")
    sec = SectionTable(stations=t["HtFract"], mass=mass, i1=2 * i23, i2=i23, i3=i23, gj=gj,
                       ei2=ei2, ei3=ei3)
    return Beam(length=height, sections=sec, damping=damping, **ELEMENTS["tower"])


def _modal_damping(deck: _Deck, module: str, vt: dict, families: dict) -> BeamDamping | None:
    """ElastoDyn's modal damping ratios (% of critical per assumed mode) as the beam's
    modal damping (model.BeamDamping.modal; fem/damping_fit.py turns them into the beam's
    Rayleigh damping by ElastoDyn's own rule)."""
    modal = {}
    for family, keys in families.items():
        ratios = [deck.number(module, k, rule=">= 0", vt=vt) for k in keys]
        for k, z in zip(keys, ratios):
            if z >= 100:
                raise TurbineFileError(deck.sources.get(module, str(deck.fst)), [
                    f"{k} = {z!r}: must be below 100 (% of critical)"])
        if any(ratios):
            modal[family] = tuple(z / 100.0 for z in ratios)
    if not modal:
        return None
    deck.notes.append(f"{module.split()[-1]}: structural damping "
                      + ", ".join(f"{f} " + "/".join(f"{100 * z:g}" for z in v) + " %"
                                  for f, v in modal.items())
                      + " of critical (ElastoDyn's modes, turned into the beam's Rayleigh "
                      "damping by its own rule: docs/structural_damping.md)")
    return BeamDamping(modal=modal)


def read_openfast(path) -> ImportResult:
    """Read an OpenFAST deck (the ``.fst`` file) into a hawt :class:`Turbine`.

    Raises :class:`TurbineFileError` naming the file and key for anything unreadable or
    unsupported; returns the turbine with the warnings and notes of the import."""
    fst = Path(path)
    if fst.suffix.lower() != ".fst":
        raise TurbineFileError(str(fst), ["an OpenFAST deck is read from its main '.fst' file"])
    if not fst.is_file():
        raise TurbineFileError(str(fst), ["file not found"])
    deck = _Deck(fst.resolve())
    comp = _main(deck)
    ed_file = deck.path(deck.fst.parent, deck.vt["Fst"]["EDFile"], "ElastoDyn")
    deck.read_keys("ElastoDyn", ed_file, lambda kf: deck.vt.__setitem__("ElastoDyn",
                                                                         dict(kf.values)))
    ed = deck.vt["ElastoDyn"]
    edn = ed_file.name
    nb = int(deck.number("ElastoDyn", "NumBl", rule="> 0"))
    if nb not in (1, 2, 3):
        raise TurbineFileError(str(ed_file), [f"NumBl = {nb}: ElastoDyn allows 1, 2 or 3"])
    flexible_tower, teeter = _check_dofs(deck, str(ed_file), nb)
    cones = [deck.number("ElastoDyn", f"PreCone({k})") for k in range(1, nb + 1)]
    if len(set(cones)) > 1:
        raise TurbineFileError(str(ed_file), [f"PreCone(1..{nb}) = {cones}: hawt's blades are "
                                              "identical; allowed: one precone for all"])
    pitches = [deck.number("ElastoDyn", f"BlPitch{k}") for k in range(1, nb + 1)]
    if len(set(pitches)) > 1:
        raise TurbineFileError(str(ed_file), [f"BlPitch(1..{nb}) = {pitches}: hawt's blades "
                                              "are identical; allowed: one pitch for all"])
    if abs(pitches[0]) > 90:
        raise TurbineFileError(str(ed_file), [f"BlPitch(1) = {pitches[0]}: allowed: -90 to "
                                              "90 degrees"])
    tips = [deck.number("ElastoDyn", f"TipMass({k})", rule=">= 0") for k in range(1, nb + 1)]
    if len(set(tips)) > 1:
        raise TurbineFileError(str(ed_file), [f"TipMass(1..{nb}) = {tips}: hawt's blades are "
                                              "identical; allowed: one tip mass for all"])
    for k in range(1, nb + 1):
        for key in (f"PBrIner({k})", f"BlPIner({k})"):
            if deck.number("ElastoDyn", key, rule=">= 0"):
                deck.warnings.append(f"{edn}: {key} = {ed[key]} read but not modelled (hawt's "
                                     "blades have no pitch degree of freedom, as ElastoDyn's)")
    tip, hubr = deck.number("ElastoDyn", "TipRad"), deck.number("ElastoDyn", "HubRad", rule=">= 0")
    if not tip > hubr:
        raise TurbineFileError(str(ed_file), [f"TipRad = {tip}: must exceed HubRad = {hubr}"])
    for key in ("HubCM", "Delta3") + (("UndSling",) if nb != 2 else ()):
        if deck.number("ElastoDyn", key):
            deck.warnings.append(f"{edn}: {key} = {ed[key]} read but not modelled (taken as 0)")
    rpm = deck.number("ElastoDyn", "RotSpeed", rule=">= 0")
    if rpm <= 0:
        raise TurbineFileError(str(ed_file), [f"RotSpeed = {rpm}: hawt needs a turning rotor "
                                              "(> 0 rpm) for its Floquet analysis"])
    tilt = math.radians(deck.number("ElastoDyn", "ShftTilt"))
    overhang = deck.number("ElastoDyn", "OverHang")
    hub_mass = deck.number("ElastoDyn", "HubMass", rule=">= 0")
    hub_iner = deck.number("ElastoDyn", "HubIner", rule="> 0")
    if nb == 2:
        i_lat = deck.number("ElastoDyn", "HubIner_Teeter", rule=">= 0") or hub_iner
        hub = Hub(radius=hubr, undersling=deck.number("ElastoDyn", "UndSling"), teeter=teeter,
                  inertia_lateral=i_lat, inertia_longitudinal=hub_iner, mass=hub_mass,
                  teeter_damping=(deck.number("ElastoDyn", "TeetDmp", rule=">= 0")
                                  if teeter and ed.get("TeetMod") == 1 else 0.0))
    else:
        # ElastoDyn's hub: a mass at the apex with inertia about the shaft only
        hub = Hub(radius=hubr, teeter=False, inertia_lateral=0.0,
                  inertia_longitudinal=hub_iner, mass=hub_mass)
    servo = servodyn_keys(deck, comp)
    yaw_k, yaw_c = yaw_spring(deck, servo)
    nac_yaw = deck.number("ElastoDyn", "NacYIner", rule=">= 0")
    cg = (deck.number("ElastoDyn", "NacCMzn"), -deck.number("ElastoDyn", "NacCMyn"),
          deck.number("ElastoDyn", "NacCMxn"))
    nacelle = Nacelle(yaw_inertia=nac_yaw + hub_yaw_share(hub, tilt, overhang),
                      yaw_stiffness=yaw_k, yaw_damping=yaw_c,
                      yaw_to_teeter=overhang, shaft_tilt=tilt,
                      yaw_free=deck.flag("ElastoDyn", "YawDOF"),
                      mass=deck.number("ElastoDyn", "NacMass", rule=">= 0"), cg_offset=cg,
                      shaft_height=deck.number("ElastoDyn", "Twr2Shft"),
                      yaw_bearing_mass=deck.number("ElastoDyn", "YawBrMass", rule=">= 0"))
    blade = _blade(deck, comp, ed_file, nb, tip - hubr)
    if tips[0]:
        blade = replace(blade, tip_mass=float(tips[0]))
        deck.notes.append(f"blade: a {tips[0]:g} kg point mass at the tip (TipMass)")
    tower = _tower(deck, ed_file, flexible_tower)
    # OpenFAST v3.1 moved Gravity from ElastoDyn's ENVIRONMENTAL CONDITION to the .fst
    if "Gravity" in deck.vt[MAIN] or "Gravity" not in ed:
        g = deck.number(MAIN, "Gravity", rule=">= 0")
    else:
        g = deck.number("ElastoDyn", "Gravity", rule=">= 0")
        deck.notes.append(f"gravity: {g:g} m/s^2 from {edn} (Gravity was ElastoDyn's before "
                          "OpenFAST v3.1)")
    name = fst.stem
    turbine = Turbine(name=name, rotor=Rotor(speed=rpm * math.pi / 30.0, blades=nb,
                                             precone=math.radians(cones[0]),
                                             pitch=-math.radians(pitches[0])),
                      hub=hub, nacelle=nacelle, blade=blade, tower=tower,
                      gravity=Gravity(enabled=g > 0, g=g if g > 0 else 9.81),
                      drivetrain=drivetrain(deck, ed_file, servo),
                      aerodynamics=_aerodynamics(deck, comp, nb, tip - hubr))
    turbine = replace(turbine, tower_aerodynamics=_tower_aerodynamics(deck, tower))
    return ImportResult(turbine=turbine, importer=IMPORTER, main_role=MAIN,
                        warnings=deck.warnings, notes=deck.notes, sources=deck.sources,
                        packages={"Examples": "rosco"})
