"""Factor groups per drive family, computed exactly from an :class:`~ecattool.scaling.model.Axis`.

Notation used in comments: ``IPR`` internal position units per motor revolution; ``cps(U)`` internal
position units per second^order for one unit ``U`` (order 1 velocity, 2 acceleration, 3 jerk);
``PF`` internal units per position unit; ``T`` Technosoft slow-loop period in seconds.
"""

from __future__ import annotations

import functools
import re
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ecattool.errors import InputError, Location, SelectionError
from ecattool.findings import Finding, Severity
from ecattool.od.types import require
from ecattool.scaling.exact import Approximation, Exact, Strategy, approximate
from ecattool.scaling.group import FactorGroup, FactorObject
from ecattool.scaling.model import Axis
from ecattool.scaling.units import Unit, dimension_notation, time_seconds

if TYPE_CHECKING:
    from ecattool.esi.model import Device
    from ecattool.od.model import ObjectDictionary
    from ecattool.scaling.group import FactorObject

FAMILIES = ("technosoft-ipos", "hdt", "controltechniques", "generic")
_FAMILY_ALIASES = {
    "technosoft": "technosoft-ipos", "ipos": "technosoft-ipos", "tml": "technosoft-ipos",
    "ct": "controltechniques", "control-techniques": "controltechniques", "sm-ethercat": "controltechniques",
    "unidrive": "controltechniques", "tomcat": "hdt", "dgfox": "hdt", "ntt": "hdt", "cia402": "generic",
}
U32 = 0xFFFFFFFF
TWO16 = 65536


def resolve_family(name: str, location: Location | None = None) -> str:
    key = name.strip().lower()
    key = _FAMILY_ALIASES.get(key, key)
    if key not in FAMILIES:
        raise SelectionError(f"unknown drive family {name!r} (one of {', '.join(FAMILIES)})", location)
    return key


def fixed_counts_per_rev(family: str) -> int | None:
    """Internal position units per motor revolution where the family fixes them whatever the encoder (HDT:
    65536, §4.05): the family's data, ``FamilyRules.counts_per_rev``; None where the feedback's counts are the
    internal unit. The one place of that rule: the factor group, ``scale explain``, the project's counts per
    unit and the scaling report all ask here."""
    from ecattool.profiles import family_rules

    return family_rules(resolve_family(family)).counts_per_rev


def technosoft_factor_set(firmware: str | None) -> str:
    """``cia402-2`` for F515K+ and FA0xx firmware, ``obsolete`` before (Technosoft §5); None → cia402-2."""
    if not firmware:
        return "cia402-2"
    fw = firmware.strip().upper()
    if fw.isdigit() and int(fw) > 0xFFFF:  # an ESI revision number in decimal (892417353 = "515I")
        fw = f"0X{int(fw):08X}"
    if fw.startswith("0X"):  # revision number = firmware name in ASCII, MSB first
        try:
            fw = bytes.fromhex(fw[2:].rjust(8, "0")).decode("ascii")
            fw = "F" + fw if not fw.startswith("F") else fw
        except (ValueError, UnicodeDecodeError):
            return "cia402-2"
    if fw.startswith("FA"):
        return "cia402-2"
    m = re.fullmatch(r"F?(\d{3})([A-Z]?)", fw)
    if not m:
        return "cia402-2"
    number, letter = int(m.group(1)), m.group(2) or "A"
    if number > 515 or (number == 515 and letter >= "K"):
        return "cia402-2"
    return "obsolete"


class _Ctx:
    """Shared arithmetic of one computation."""

    def __init__(self, axis: Axis, internal_per_motor_rev: Exact) -> None:
        self.axis = axis
        self.ipr = internal_per_motor_rev
        self.u = axis.units
        self.pf = axis.internal_per_unit(self.u[0], self.ipr)

    def cps(self, order: int) -> Exact:
        """Internal units per second^order for one user unit of that order."""
        unit = self.u[order]
        return self.axis.internal_per_unit(unit, self.ipr) / unit.time_s

    @property
    def feed(self) -> Exact:
        """Feed constant 6092h: position units per driving-shaft revolution (= G * IPR / PF)."""
        return self.axis.gear.ratio * self.ipr / self.pf


def _types(device: Device | None, family: str, firmware: str | None = None) -> ObjectDictionary | None:
    """The object dictionary to take types from: the given device's, else the built-in profile's, else None."""
    if device is not None:
        return device.dictionary
    if family == "generic":
        return None
    return _profile_dictionary(family, firmware)


@functools.lru_cache(maxsize=16)
def _profile_dictionary(family: str, firmware: str | None) -> ObjectDictionary | None:
    try:
        from ecattool.profiles import load
    except ImportError:
        return None
    try:
        return load(family, revision=firmware).dictionary if firmware else load(family).dictionary
    except Exception:  # a profile not built yet: fall back to the manuals' types
        return None


class _Builder:
    def __init__(self, group: FactorGroup, dictionary: ObjectDictionary | None, strategy: Strategy,
                 location: Location | None) -> None:
        self.g = group
        self.od = dictionary
        self.strategy = strategy
        self.loc = location

    def _type(self, index: int, sub: int, default: str) -> str | None:
        """Type name from the dictionary; None when the dictionary lacks the object (it is then skipped)."""
        if self.od is None:
            return default
        entry = self.od.entry(index, sub)
        if entry is None:
            if self.od.get(index) is None:
                return None
            return default
        dt = getattr(entry, "datatype", None)
        return dt.name if dt is not None else default

    def _skip(self, index: int, name: str) -> None:
        self.g.notes.append(f"0x{index:04X} {name}: not in the drive's dictionary, not written")

    def pair(self, index: int, name: str, parts: tuple[str, str], value: Exact | Fraction, meaning: str,
             default_type: str = "UDINT", scale_exact: bool = False, write: bool = True,
             strategy: Strategy | None = None) -> Approximation | None:
        type_name = self._type(index, 1, default_type)
        if type_name is None:
            self._skip(index, name)
            return None

        rng = require(type_name).range() or (0, U32)
        hi = rng[1]
        approx = approximate(Exact.of(value), hi, hi, strategy or self.strategy, scale_exact,
                             f"0x{index:04X} {name}", self.loc)
        self.g.add_pair(index, name, parts, approx, meaning, type_name, write)
        if not approx.exact:
            self.g.findings.append(Finding(
                "scaling.approximated", Severity.INFO,
                f"0x{index:04X} {name} = {approx.numerator}/{approx.denominator} approximates {approx.exact_value} "
                f"({float(approx.ppm):+.3g} ppm, {float(approx.drift):+.4g} per 10^6 units)",
                self.loc, {"index": index, "ppm": float(approx.ppm), "drift": float(approx.drift)}))
        return approx

    def single(self, index: int, sub: int, name: str, value: int, meaning: str, default_type: str) -> None:
        type_name = self._type(index, sub, default_type)
        if type_name is None:
            self._skip(index, name)
            return
        self.g.add(index, sub, name, value, meaning, type_name)

    def si(self, index: int, name: str, unit: Unit) -> None:
        word = unit.si_word()
        if word is None:
            self.g.notes.append(f"0x{index:04X} {name}: {unit.text!r} has no SI notation word; left unchanged")
            return
        self.single(index, 0, name, word, f"unit {unit.text} (informative)", "UDINT")


def _fmt(x: Exact) -> str:
    return str(x) if x.is_rational else f"{x} ≈ {float(x.rational):.10g}"


def compute(axis: Axis, family: str = "technosoft-ipos", *, firmware: str | None = None,
            factor_set: str | None = None, device: Device | None = None, strategy: Strategy | None = None,
            vl: bool | None = None, vl_setpoint: tuple[int, int] = (1, 1)) -> FactorGroup:
    """Every scaling object of ``axis`` for ``family``.

    ``firmware`` (Technosoft: ``F515I`` → obsolete factor set, ``F515K``/``FA00x`` → CiA-402-2) or
    ``factor_set`` override the choice. ``device`` (an ESI/profile Device) supplies object types and
    filters objects the drive lacks. ``strategy`` chooses the approximation of non-representable ratios
    (Technosoft default ``max-scale``, else ``best``). ``vl`` adds the vl velocity factors 604Bh/604Ch
    (default: Control Techniques only).
    """
    fam = resolve_family(family, axis.source)
    if fam == "technosoft-ipos":
        fs = factor_set or technosoft_factor_set(firmware)
    else:
        fs = {"hdt": "hdt", "controltechniques": "controltechniques", "generic": "generic"}[fam]
    if fs not in ("cia402-2", "obsolete", "hdt", "controltechniques", "generic"):
        raise InputError(f"unknown factor set {fs!r}", axis.source)
    group = FactorGroup(fam, fs, source=axis.source)
    od = _types(device, fam, firmware if fam == "technosoft-ipos" else None)
    if od is not None and fam == "technosoft-ipos" and firmware is None and fs == "obsolete":
        od = _types(None, fam, "F515I")
    strat: Strategy = strategy or ("max-scale" if fam == "technosoft-ipos" else "best")
    b = _Builder(group, od, strat, axis.source)
    fixed = fixed_counts_per_rev(fam)
    ipr = Exact(Fraction(fixed)) if fixed is not None else axis.counts_per_motor_rev
    ctx = _Ctx(axis, ipr)
    _summary(group, axis, ctx, fam)
    if axis.transmission.kind in ("hollow_shaft", "linear_motor") and axis.gear.ratio != 1:
        group.findings.append(Finding("scaling.gear-ignored", Severity.WARNING,
                                      f"a {axis.transmission.kind} axis has no gearbox, but gear {axis.gear} was given",
                                      axis.source))
    if fs == "cia402-2":
        _technosoft_402_2(b, ctx)
    elif fs == "obsolete":
        _technosoft_obsolete(b, ctx)
    elif fs == "hdt":
        _hdt(b, ctx, bool(vl))
    elif fs == "controltechniques":
        _controltechniques(b, ctx, vl is not False, vl_setpoint)
    else:
        _generic(b, ctx, od, device)
    if fam == "technosoft-ipos":
        _check_small_pairs(group, (0x6093, 0x6094, 0x6097, 0x2071) if fs == "obsolete" else (0x6093, 0x6094, 0x210F, 0x2110))
    return group


def _summary(g: FactorGroup, axis: Axis, ctx: _Ctx, fam: str) -> None:
    u = ctx.u
    g.summary.update({
        "feedback": axis.feedback.description,
        "transmission": axis.transmission.description,
        "gear (motor:load)": str(axis.gear),
        "internal units per motor rev": _fmt(ctx.ipr),
        "position unit": u[0].text,
        "velocity unit": u[1].text,
        "acceleration unit": u[2].text,
        "jerk unit": u[3].text,
        f"internal units per {u[0].text}": _fmt(ctx.pf),
        f"internal units/s per {u[1].text}": _fmt(ctx.cps(1)),
        f"internal units/s² per {u[2].text}": _fmt(ctx.cps(2)),
    })
    if fam == "technosoft-ipos":
        g.summary["slow loop T [s]"] = axis.slow_loop


# --- Technosoft, CiA-402-2 (F515K / FA0xx and newer; §5.2) ------------------------------------------------


def _polarity(b: _Builder, ctx: _Ctx, always: bool = True) -> None:
    if ctx.axis.reverse or always:
        value = 0xC0 if ctx.axis.reverse else 0
        b.single(0x607E, 0, "Polarity", value,
                 "bit7 positions x -1, bit6 velocities x -1" if value else "positions and velocities not inverted", "USINT")


def _technosoft_402_2(b: _Builder, ctx: _Ctx) -> None:
    ax, u, T = ctx.axis, ctx.u, Exact(ctx.axis.slow_loop)
    b.pair(0x608F, "Position encoder resolution", ("Encoder increments", "Motor rotation"), ctx.ipr,
           "encoder increments per motor revolution", strategy="best")
    b.pair(0x6091, "Gear ratio", ("Motor rotation", "Load rotation"), ax.gear.ratio,
           "motor revolutions per load (driving shaft) revolution", strategy="best")
    b.pair(0x6092, "Feed constant", ("Feed", "Shaft rotations"), ctx.feed,
           f"{u[0].text} per driving-shaft revolution", strategy="best")
    b.pair(0x6093, "Position factor", ("Position internal units (IU)", "Position units (PU)"), ctx.pf,
           f"IU per {u[0].text}: IU = PU x 608F x 6091 / 6092", scale_exact=True)
    b.pair(0x6096, "Velocity factor", ("Velocity units (VU)", "Position units (PU)"), ctx.pf / ctx.cps(1),
           f"{u[1].text} per ({u[0].text}/s)", strategy="best")
    b.pair(0x6094, "Velocity encoder factor", ("Velocity internal units (IU)", "Velocity units (VU)"),
           ctx.cps(1) * T * TWO16, f"IU (1/65536 count per slow loop) per {u[1].text}: 6093/6096 x T x 2^16",
           scale_exact=True)
    b.pair(0x6097, "Acceleration factor", ("Acceleration units (AU)", "Velocity units (VU)"), ctx.cps(1) / ctx.cps(2),
           f"{u[2].text} per ({u[1].text}/s)", strategy="best")
    b.pair(0x210F, "Acceleration encoder factor", ("Acceleration internal units (IU)", "Acceleration units (AU)"),
           ctx.cps(2) * T * T * TWO16, f"IU (1/65536 count per slow loop²) per {u[2].text}: 6094/6097 x T",
           scale_exact=True)
    b.pair(0x60A2, "Jerk factor", ("Jerk units (JU)", "Acceleration units (AU)"), ctx.cps(2) / ctx.cps(3),
           f"{u[3].text} per ({u[2].text}/s)", strategy="best")
    b.pair(0x2110, "Jerk encoder factor", ("Jerk internal units (IU)", "Jerk units (JU)"),
           ctx.cps(3) * T * T * T * TWO16, f"IU per {u[3].text}: 210F/60A2 x T", scale_exact=True)
    for index, name, unit in ((0x60A8, "SI unit position", u[0]), (0x60A9, "SI unit velocity", u[1]),
                              (0x60AA, "SI unit acceleration", u[2]), (0x60AB, "SI unit jerk", u[3])):
        b.si(index, name, unit)
    _polarity(b, ctx)


# --- Technosoft, obsolete CiA-402 (before F515K; §5.1) ---------------------------------------------------


def _technosoft_obsolete(b: _Builder, ctx: _Ctx) -> None:
    ax, u, T = ctx.axis, ctx.u, Exact(ctx.axis.slow_loop)
    b.pair(0x6093, "Position factor", ("Numerator", "Divisor"), ctx.pf, f"IU (counts) per {u[0].text}", scale_exact=True)
    b.pair(0x6094, "Velocity encoder factor", ("Numerator", "Divisor"), ctx.cps(1) * T * TWO16,
           f"IU (1/65536 count per slow loop) per {u[1].text}", scale_exact=True)
    b.pair(0x6097, "Acceleration factor", ("Numerator", "Divisor"), ctx.cps(2) * T * T * TWO16,
           f"IU (1/65536 count per slow loop²) per {u[2].text}", scale_exact=True)
    tu = time_seconds("1" + ax.time, ax.source)
    b.pair(0x2071, "Time factor", ("Numerator", "Divisor"), Exact(tu) / T,
           f"slow-loop samples per {ax.time}", scale_exact=True)
    # writing non-zero dimension (and notation) indices activates the factors (§5.1, decisions.md)
    for (dim_i, not_i, label, unit) in ((0x608A, 0x6089, "position", u[0]), (0x608C, 0x608B, "velocity", u[1]),
                                        (0x608E, 0x608D, "acceleration", u[2]), (0x2070, 0x206F, "time", ax.time)):
        dim, notation, listed = dimension_notation(unit)
        text = unit.text if isinstance(unit, Unit) else unit
        how = "Appendix B" if listed else "custom unit: 1 activates the factor"
        b.single(dim_i, 0, f"{label.capitalize()} dimension index", dim, f"{text} ({how})", "USINT")
        b.single(not_i, 0, f"{label.capitalize()} notation index", notation, f"{text} ({how})", "SINT")
    if ax.jerk is not None:
        b.g.notes.append("obsolete factor set has no jerk units: jerk is set as a time (2023h, scaled by 2071h)")
    _polarity(b, ctx)


# --- HDT (obsolete CiA-402 objects, 65536 counts per motor revolution; §4.05) -------------------------------

_HDT_APPLICATIONS = {
    "rotary": "0 - disk axis (angular measurement)",
    "belt": "2 - conveyor belt, flat (pulley diameter) / 3 - conveyor belt, toothed (teeth x pitch)",
    "rack": "3 - conveyor belt, toothed (teeth x pitch) / 1 - disk axis, linear measurement (diameter)",
    "ballscrew": "6 - axis with worm (screw pitch)",
    "hollow_shaft": "7 - motor with hollow shaft (screw pitch)",
    "linear_motor": "linear motor application (pole pitch)",
    "label": "Custom (label)",
}


def _hdt(b: _Builder, ctx: _Ctx, vl: bool) -> None:
    u = ctx.u
    b.pair(0x6093, "Position factor", ("Numerator", "Feed constant"), ctx.pf,
           f"internal pulses (65536/motor rev) per {u[0].text}")
    b.pair(0x6094, "Velocity encoder factor", ("Numerator", "Divisor"), ctx.cps(1),
           f"pulses/s per {u[1].text}")
    b.pair(0x6097, "Acceleration factor", ("Numerator", "Divisor"), ctx.cps(2),
           f"pulses/s² per {u[2].text} (also jerk 2011h: pulses/s³ per {u[2].text}/s)")
    if vl:
        _vl_dimension(b, ctx, "DINT", 0x7FFFFFFF)
    _polarity(b, ctx)
    tr = ctx.axis.transmission
    app = _HDT_APPLICATIONS.get(tr.kind, "")
    if tr.kind == "rotary" and tr.travel != 1:
        app = "4/5 - transmission axis (flat / toothed belt stage)"
    b.g.summary["Caliper application"] = app
    if ctx.axis.transmission.kind == "label":
        b.g.summary["Caliper custom label"] = f"{ctx.axis.transmission.label}: {ctx.axis.transmission.travel} per motor rev"
    b.g.notes.append("HDT notation/dimension indices 6089h-608Eh are fixed and informative: not written")
    if ctx.axis.jerk is not None and ctx.u[3].time_s != ctx.u[2].time_s:
        b.g.notes.append(f"HDT jerk 2011h is in {u[2].text}/s (scaled by 6097h), not {u[3].text}")


def _vl_dimension(b: _Builder, ctx: _Ctx, type_name: str, limit: int) -> None:
    rpm_per_vu = ctx.cps(1) * 60 / ctx.ipr  # motor revolutions per minute for one velocity unit
    b.pair(0x604C, "vl dimension factor", ("Numerator", "Denominator"), rpm_per_vu,
           f"motor rpm per {ctx.u[1].text} (rpm = 6042h x 604B x 604C)", default_type=type_name)


# --- Control Techniques SM-EtherCAT (608F RO, 6091h, 6092h, vl 604Bh/604Ch; §7.3.10-13, §7.5) ----------------


def _controltechniques(b: _Builder, ctx: _Ctx, vl: bool, setpoint: tuple[int, int]) -> None:
    u = ctx.u
    b.pair(0x608F, "Position encoder resolution", ("Encoder increments", "Motor revolutions"), ctx.ipr,
           "read-only: read from the drive's encoder configuration; expected value", write=False)
    b.pair(0x6091, "Gear ratio", ("Motor revolutions", "Shaft revolutions"), ctx.axis.gear.ratio,
           "motor revolutions per driving-shaft revolution")
    feed = b.pair(0x6092, "Feed constant", ("Feed", "Shaft revolutions"), ctx.feed,
                  f"{u[0].text} per driving-shaft revolution")
    res, gear = b.g.ratio(0x608F), b.g.ratio(0x6091)
    if feed is not None and res is not None and gear is not None:
        effective = res * gear / feed.value
        b.g.summary["position factor (drive computes 608F x 6091 / 6092)"] = effective
        if effective != ctx.pf.rational:
            err = (effective - ctx.pf.rational) / ctx.pf.rational * 1_000_000
            b.g.summary["position factor error [ppm]"] = float(err)
    if vl:
        if not all(-32768 <= v <= 32767 and v for v in setpoint):
            raise InputError(f"vl setpoint factor {setpoint[0]}/{setpoint[1]} must be a non-zero 16-bit ratio", b.loc)
        b.g.objects.append(_setpoint_object(0x604B, 1, setpoint[0]))
        b.g.objects.append(_setpoint_object(0x604B, 2, setpoint[1]))
        _vl_dimension(b, ctx, "INT", 0x7FFF)
    b.g.notes.append("SM-EtherCAT velocities other than vl use the same position constants (no 6094h/6096h)")
    if ctx.axis.reverse:
        b.g.findings.append(Finding("scaling.no-polarity", Severity.WARNING,
                                    "SM-EtherCAT has no polarity object 607Eh: reverse the motor direction in the drive "
                                    "(or use a negative vl setpoint factor 604Bh for vl mode)", b.loc))


def _setpoint_object(index: int, sub: int, value: int) -> FactorObject:
    return FactorObject(index, sub, "vl setpoint factor", ("Numerator", "Denominator")[sub - 1], value, "INT",
                        "resolution of 6042h (not applied to limits and ramps)")


# --- generic CiA-402-2 drives ---------------------------------------------------------------------------------


def _generic(b: _Builder, ctx: _Ctx, od: ObjectDictionary | None, device: Device | None = None) -> None:
    u = ctx.u
    enc, gear, feed = ctx.ipr, Exact.of(ctx.axis.gear.ratio), ctx.feed
    meanings = {0x608F: "encoder increments per motor revolution",
                0x6091: "motor revolutions per driving-shaft revolution",
                0x6092: f"{u[0].text} per driving-shaft revolution"}
    have = {i: od is None or od.get(i) is not None for i in (0x608F, 0x6091, 0x6092, 0x6093)}
    missing = [i for i in (0x608F, 0x6091, 0x6092) if not have[i]]
    if not have[0x6093] and missing:
        # the drive computes its position factor from 608Fh x 6091h / 6092h alone and takes an object it lacks
        # as 1 (Inovance SV660N: 6091h only): the ratio of a missing object goes into one it has, else the
        # drive would move by the gear ratio alone
        carrier = next((i for i in (0x6091, 0x608F, 0x6092) if have[i]), None)
        if carrier is None and ctx.pf == 1:
            pass  # the user's position unit is the drive's increment: nothing to set
        elif carrier is None:
            source = device.source if device is not None else ""
            raise InputError("the device has none of the scaling objects that set user units (608Fh, 6091h, 6092h, "
                             f"6093h): its positions stay in its own units, and 1 {u[0].text} = {_fmt(ctx.pf)} "
                             "increments cannot be set (leave out the scaling, or use the drive's units)",
                             Location(source) if source and not source.startswith("profile:") else b.loc)
        else:
            numerators = (enc if have[0x608F] and carrier != 0x608F else Exact.of(1)) \
                * (gear if have[0x6091] and carrier != 0x6091 else Exact.of(1))
            if carrier == 0x6092:
                feed = numerators / ctx.pf
            elif carrier == 0x6091:
                gear = ctx.pf * (feed if have[0x6092] else Exact.of(1)) / numerators
            else:
                enc = ctx.pf * (feed if have[0x6092] else Exact.of(1)) / numerators
            lacks = " and ".join(f"{i:04X}h" for i in missing if i != carrier)
            meanings[carrier] = f"{_fmt(ctx.pf)} increments per {u[0].text} with {lacks} (not in the drive: taken as 1)"
            b.g.notes.append(f"0x{carrier:04X} carries the ratio of {lacks}: the drive has no such object, and takes "
                             "it as 1")
    if od is not None:
        # without 6096h/6097h the drive takes velocities in position units per second and accelerations in
        # velocity units per second: another unit would be off by the factor nobody writes (rpm on an Inovance)
        for index, factor, unit, natural in ((0x6096, ctx.pf / ctx.cps(1), u[1], f"{u[0].text}/s"),
                                             (0x6097, ctx.cps(1) / ctx.cps(2), u[2], f"{u[1].text}/s")):
            absent = od.get(index) is None and (index != 0x6096 or od.get(0x6094) is None)
            if absent and factor != 1:
                raise InputError(f"the device has no {index:04X}h: it takes {unit.text} as {natural}, which is not "
                                 f"the same unit (write {natural}, or use a drive with {index:04X}h)", b.loc)
    b.pair(0x608F, "Position encoder resolution", ("Encoder increments", "Motor revolutions"), enc, meanings[0x608F])
    b.pair(0x6091, "Gear ratio", ("Motor revolutions", "Shaft revolutions"), gear, meanings[0x6091])
    b.pair(0x6092, "Feed constant", ("Feed", "Shaft revolutions"), feed, meanings[0x6092])
    b.pair(0x6093, "Position factor", ("Numerator", "Divisor"), ctx.pf, f"increments per {u[0].text}")
    if od is not None and od.get(0x6094) is not None:
        b.pair(0x6094, "Velocity encoder factor", ("Numerator", "Divisor"), ctx.cps(1), f"increments/s per {u[1].text}")
    b.pair(0x6096, "Velocity factor", ("Numerator", "Divisor"), ctx.pf / ctx.cps(1), f"{u[1].text} per ({u[0].text}/s)")
    b.pair(0x6097, "Acceleration factor", ("Numerator", "Divisor"), ctx.cps(1) / ctx.cps(2), f"{u[2].text} per ({u[1].text}/s)")
    b.pair(0x60A2, "Jerk factor", ("Numerator", "Divisor"), ctx.cps(2) / ctx.cps(3), f"{u[3].text} per ({u[2].text}/s)")
    for index, name, unit in ((0x60A8, "SI unit position", u[0]), (0x60A9, "SI unit velocity", u[1]),
                              (0x60AA, "SI unit acceleration", u[2]), (0x60AB, "SI unit jerk", u[3])):
        b.si(index, name, unit)
    if ctx.axis.reverse:
        _polarity(b, ctx, always=False)


def _check_small_pairs(g: FactorGroup, indices: tuple[int, ...]) -> None:
    """Technosoft §5.1.10.1: small numerator/divisor pairs are computed with round-off; say so."""
    for index in indices:
        p = g.pair(index)
        if p and max(p) < 0x10000:
            g.findings.append(Finding("scaling.small-pair", Severity.WARNING,
                                      f"0x{index:04X} = {p[0]}/{p[1]}: Technosoft computes small pairs with round-off; "
                                      "use large values with the same ratio", g.source))
