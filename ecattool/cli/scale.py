"""``ecattool scale``: CiA-402 factor groups from mechanics and units (thin: the logic is in ecattool.scaling)."""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Literal

import click

from ecattool.cli.common import (
    Decorated,
    console,
    dump_json,
    file_output_option,
    json_option,
    output_option,
    policy_option,
    print_json,
    table,
    write_output,
)
from ecattool.cli.online import reset_bus_given, reset_bus_option
from ecattool.cli.paths import InputFile
from ecattool.cli.startup import lossy_option, write_startup
from ecattool.cli.vocab import WRITE_FORMATS, device_option, shared_option
from ecattool.errors import InputError, Location, SelectionError

_FAMILIES = ("technosoft-ipos", "hdt", "controltechniques", "generic")
_STARTUP_FORMATS = WRITE_FORMATS

if TYPE_CHECKING:
    from ecattool.scaling.exact import Strategy
    from ecattool.scaling.explain import Explanation
    from ecattool.scaling.group import FactorGroup
    from ecattool.scaling.spec import Spec
    from ecattool.target.base import SlaveTarget


def _mechanics_options(f: Decorated) -> Decorated:
    opts: list[Callable[[Decorated], Decorated]] = [
        click.argument("spec", required=False, type=InputFile(allow_dash=True)),
        shared_option("--profile", "family", type=click.Choice(_FAMILIES),
                      help="Drive family (default: the spec's, else technosoft-ipos)."),
        click.option("--firmware", help="Technosoft firmware, e.g. F515I (obsolete factors) or F515K (CiA-402-2)."),
        shared_option("--counts-per-rev", "counts", help="Feedback increments per revolution (e.g. 2000)."),
        click.option("--lines", help="Quadrature encoder lines (x4 = counts), e.g. 500."),
        click.option("--steps", help="Stepper: STEPSxMICROSTEPS, e.g. 200x256."),
        click.option("--feedback-on", type=click.Choice(["motor", "load"]), help="Where the feedback sits (default motor)."),
        click.option("--gear", help="Gearbox motor:load revolutions, e.g. 3:1."),
        click.option("--transmission", help="e.g. 'ballscrew pitch=5mm', 'belt teeth=20 tooth_pitch=5mm', "
                                            "'belt diameter=30mm', 'rack teeth=20 module=2mm', 'linear_motor pole_pitch=32mm'."),
        click.option("--position", "pos_unit", help="Position unit (mm, um, deg, rad, rev, inch, counts …)."),
        click.option("--velocity", "vel_unit", help="Velocity unit (mm/s, rpm, deg/s …; default position/s)."),
        click.option("--acceleration", "acc_unit", help="Acceleration unit (mm/s^2, rpm/s …)."),
        click.option("--jerk", "jerk_unit", help="Jerk unit (mm/s^3 …)."),
        click.option("--slow-loop", help="Technosoft slow-loop period (default 1ms)."),
        click.option("--reverse", is_flag=True, default=None, help="Invert positions and velocities (607Eh)."),
        click.option("--approximation", type=click.Choice(["best", "max-scale"]),
                     help="How to approximate non-representable ratios (Technosoft default max-scale, others best)."),
        click.option("--vl/--no-vl", default=None, help="Add the vl velocity factors 604Bh/604Ch (default: Control Techniques only)."),
        click.option("--esi", type=InputFile(),
                     help="ESI file of the drive: object types from its dictionary, objects it lacks left out."),
        device_option(),
        policy_option,
    ]
    for o in reversed(opts):
        f = o(f)
    return f


def _spec(spec: str | None, family: str | None, firmware: str | None, counts: str | None, lines: str | None,
          steps: str | None, feedback_on: Literal["motor", "load"] | None, gear: str | None, transmission: str | None,
          pos_unit: str | None,
          vel_unit: str | None, acc_unit: str | None, jerk_unit: str | None, slow_loop: str | None,
          reverse: bool | None,
          approximation: Strategy | None) -> tuple[Spec, str, str | None, Strategy | None]:
    """(the spec the flags say, over SPEC where given; the family, firmware and approximation to use)."""
    from ecattool.scaling.model import length_unit, transmission_from
    from ecattool.scaling.spec import AxisOptions, load_spec, spec_with

    base = load_spec(spec) if spec else None
    if steps and "x" not in steps.lower():
        raise click.BadParameter("write STEPSxMICROSTEPS, e.g. 200x256", param_hint="--steps")
    if transmission:  # a mechanics string the user typed: its error names the option
        try:
            transmission_from(transmission, meant=length_unit(pos_unit or (base.axis.position if base else None)))
        except InputError as exc:
            raise click.BadParameter(exc.message, param_hint="'--transmission'") from None
    stepper = steps.lower().split("x", 1) if steps else None
    parsed = spec_with(base, AxisOptions(counts, lines, (stepper[0], stepper[1]) if stepper else None, feedback_on,
                                         gear, transmission, pos_unit, vel_unit, acc_unit, jerk_unit, slow_loop,
                                         reverse))
    fam = family or parsed.family or "technosoft-ipos"
    return parsed, fam, firmware or parsed.firmware, approximation or parsed.approximation


def _compute(kwargs: dict[str, Any]) -> FactorGroup:
    from ecattool.scaling import compute

    vl = kwargs.pop("vl")
    esi, selector, policy = kwargs.pop("esi"), kwargs.pop("selector"), kwargs.pop("policy")
    device = None
    if esi:
        from ecattool.profiles import family_of
        from ecattool.project.machine import Machine

        # the device of the one-slave machine --esi/--device/--policy build, as a project entry would
        device = Machine.from_device_flags(esi=esi, select=selector, policy=policy).slaves[0].require_device()
        if not kwargs.get("family"):
            kwargs["family"] = family_of(device)
    spec, family, firmware, approximation = _spec(**kwargs)
    return compute(spec.axis, family, firmware=firmware, strategy=approximation, vl=vl, vl_setpoint=spec.vl_setpoint,
                   device=device)


_HTML_HELP = ("Also write the factor-group derivation as a page to FILE: encoder -> gear -> transmission -> user "
              "unit as a chain, what the units mean, the values and findings (docs/report.md). Needs "
              "pip install 'ecattool[report]'.")


def _html_prerequisites(html: str | None, json_to_stdout: bool) -> None:
    """Before any work: the report extra is there, and the page and JSON do not both go to stdout."""
    if not html:
        return
    from ecattool.report import require

    require("jinja2")
    if html == "-" and json_to_stdout:
        raise click.UsageError("--html - and the JSON output cannot both go to stdout")


def _render(group: FactorGroup) -> None:
    con = console()
    t = table(f"Factor group — {group.family} ({group.factor_set})", ["object", "name", "part", "value", "hex", "exact", "meaning"],
              optional=("name", "exact"))
    for o in group.objects:
        a = o.approximation
        exact = "yes" if o.exact else f"≈ {float(a.ppm):+.3g} ppm" if a else "no"
        meaning = o.meaning + ("" if o.write else " [not written]")
        t.add_row(o.address, o.name, o.part, str(o.value), o.hex, exact, meaning)
    con.print(t)
    s = table("Axis", ["quantity", "value"])
    for k, v in group.summary.items():
        s.add_row(k, str(v))
    con.print(s)
    for n in group.notes:
        con.print(f"note: {n}")
    for f in group.findings:
        con.print(f"{f.severity.value}: {f.message}" + (f" [{f.rule}]" if not f.data else ""))


@click.group("scale", epilog="""\b
Examples:
  ecattool scale compute samples/scaling/ballscrew.yaml
  ecattool scale compute --lines 500 --position rad --firmware F515I
  ecattool scale startup samples/scaling/belt.yaml --format twincat
  ecattool scale explain --profile technosoft-ipos 6093:01=4294967295 6093:02=13493038
  ecattool scale si mm rpm 0x03105700""")
def scale() -> None:
    """Compute CiA-402 factor groups from mechanics and units, exactly.

    From feedback, gearbox, transmission and the units you want, computes every scaling object of a
    drive family (Technosoft iPOS CiA-402-2 or obsolete set, HDT, Control Techniques SM-EtherCAT, generic
    CiA-402-2), says which values are exact and how far approximated ones drift, writes the startup list,
    and explains values read back from a drive.
    """


@scale.command("compute", epilog="""\b
Examples:
  ecattool scale compute samples/scaling/ballscrew.yaml
  ecattool scale compute samples/scaling/belt.yaml --profile hdt --json
  ecattool scale compute --lines 500 --position rev --velocity rpm --acceleration rev/s^2
  ecattool scale compute --counts-per-rev 4096 --gear 3:1 --transmission 'ballscrew pitch=10mm' \\
      --position mm --profile controltechniques
  ecattool scale compute --lines 500 --position rad --firmware F515I   # 4294967295 / 13493038
  ecattool scale compute samples/scaling/rotary_table.yaml --esi copley_XE2_4.60.xml
  ecattool scale compute samples/scaling/ballscrew.yaml --html scaling.html   # the chain as a page""")
@_mechanics_options
@click.option("--startup", "with_startup", is_flag=True, help="Also print the startup list (transition PS).")
@json_option
@output_option()
@file_output_option("--html", "html", help=_HTML_HELP)
def compute_cmd(with_startup: bool, as_json: bool, output: str | None, html: str | None, **kwargs: Any) -> None:
    """Table of scaling objects: value (decimal, hex), meaning, exactness; approximations with ppm error."""
    _html_prerequisites(html, as_json or output == "-")
    inputs = tuple(kwargs[k] for k in ("spec", "esi") if kwargs.get(k) not in (None, "-"))
    group = _compute(kwargs)
    if html:
        from ecattool.report import scaling_html
        from ecattool.scaling.explain import explain_group

        write_output(html, scaling_html(explain_group(group), group.values, group.mechanics,
                                        title=str(kwargs.get("spec") or "")), inputs)
        if html == "-":
            return
    if as_json or output:
        _write_json(group, with_startup, output, inputs)
        return
    _render(group)
    if with_startup:
        from ecattool.startup import export

        click.echo(export(group.startup(), "twincat"), nl=False)


def _write_json(group: FactorGroup, with_startup: bool, output: str | None, inputs: tuple[str, ...]) -> None:
    """The group as JSON (with its startup writes where asked for), to ``output`` or stdout."""
    data = group.to_json()
    if with_startup:
        data["startup"] = [{"transition": c.transition, "index": f"0x{c.index:04X}", "subindex": c.subindex,
                            "data": c.data.hex(), "type": c.type_name, "value": c.value, "comment": c.comment}
                           for c in group.startup()]
    if output:
        write_output(output, dump_json(data) + "\n", inputs)
    else:
        print_json(data)


@scale.command("startup", epilog="""\b
Examples:
  ecattool scale startup samples/scaling/ballscrew.yaml
  ecattool scale startup samples/scaling/rotary_table.yaml --format igh -o scaling.c
  ecattool scale startup samples/scaling/ballscrew.yaml --format eni --lossy -o drive_startup.xml
  ecattool scale startup --lines 500 --position deg --format json""")
@_mechanics_options
@click.option("--format", "fmt", type=click.Choice(_STARTUP_FORMATS), default="twincat", show_default=True,
              help="Startup-list format (the master's).")
@click.option("--transition", default="PS", show_default=True, help="EtherCAT transition of the writes.")
@lossy_option
@output_option()
def startup_cmd(fmt: str, transition: str, lossy: bool, output: str | None, **kwargs: Any) -> None:
    """The SDO writes that set the factor group, in a master's startup-list format (an ENI needs the drive's
    identity, which a spec without --esi does not give: --lossy writes it without)."""
    from ecattool.startup import TRANSITIONS

    if transition.upper() not in TRANSITIONS:
        raise click.BadParameter(f"one of {', '.join(TRANSITIONS)}", param_hint="--transition")
    inputs = tuple(kwargs[k] for k in ("spec", "esi") if kwargs.get(k) not in (None, "-"))
    esi = kwargs.get("esi")
    group = _compute(kwargs)
    commands = group.startup(transition.upper())
    if not commands:  # e.g. an ESI whose dictionary has none of the factor objects: say so, do not write nothing

        raise InputError("the device has none of the scaling objects (608Fh, 6091h-6097h, 60A2h, 60A8h-60ABh); "
                         "no startup list to write", Location(esi) if esi else None)
    write_startup([commands], fmt, output, inputs, lossy)


@scale.command("explain", epilog="""\b
Examples:
  ecattool scale explain --profile technosoft-ipos 6093:01=4294967295 6093:02=13493038
  ecattool scale explain --profile hdt 6093:01=65536 6093:02=360 6094:01=65536 6094:02=60
  ecattool scale explain --profile controltechniques 608F:01=4096 6091:01=3 6092:01=10 604C:01=60
  ecattool scale explain --profile technosoft-ipos --from drive_startup.xml --json
  ecattool scale explain --profile hdt --target sim
  ecattool scale explain --profile technosoft-ipos --target pysoem:eth0 --slave 2
  ecattool scale explain --profile hdt 6093:01=16384 6093:02=25 --html scaling.html
  ecattool scale explain --project samples/hdt/project.yaml           # what the project's startup list sets""")
@click.argument("assignments", nargs=-1)
@shared_option("--profile", "family", type=click.Choice(_FAMILIES), default="technosoft-ipos", show_default=True,
               help="Drive family the values are for.")
@click.option("--from", "source", type=InputFile(),
              help="Read values from a startup file (any format), a `scale compute --json` file or a YAML mapping.")
@click.option("--target", help="Read the values from a drive: 'sim' (the family's simulated drive) or 'pysoem:IFACE'.")
@reset_bus_option
@click.option("--slave", type=int, default=0, show_default=True, help="Bus position of the drive (with --target).")
@click.option("--project", type=InputFile(), help="Read the values a project's drive holds after its startup list "
              "(its writes, else the device's defaults) and take its family.")
@click.option("--drive", "drive_name", help="Drive name in --project (needed when it has several).")
@click.option("--allow-errors", is_flag=True, help="With --project: explain even when lint reports errors for the drive.")
@click.option("--firmware", help="Technosoft firmware (F515I → obsolete factor set).")
@click.option("--slow-loop", default="1ms", show_default=True, help="Technosoft slow-loop period.")
@shared_option("--counts-per-rev", "counts_per_rev", help="Increments per motor revolution, to express velocities in rpm.")
@json_option
@file_output_option("--html", "html", help=_HTML_HELP)
def explain_cmd(assignments: tuple[str, ...], family: str, source: str | None, target: str | None, slave: int,
                project: str | None, drive_name: str | None, allow_errors: bool,
                firmware: str | None, slow_loop: str, counts_per_rev: str | None, as_json: bool,
                html: str | None) -> None:
    """What one user unit is in counts, and what velocity and acceleration units mean, from object values."""
    from ecattool.scaling import explain
    from ecattool.scaling.explain import read_values, values_from_file
    from ecattool.scaling.model import slow_loop_from

    _html_prerequisites(html, as_json)
    values = values_from_file(source) if source else {}
    if project:
        held, family = _project_values(project, drive_name, allow_errors, family)
        values, source = {**values, **held}, source or project
    elif drive_name is not None:
        raise click.UsageError("--drive needs --project")
    if target:
        values.update(read_values(_target_slave(target, family, slave, firmware)))
    values.update(_assignments(assignments))
    if not values:
        raise InputError("give object values (6093:01=… 6093:02=…) or --from FILE")
    e = explain(values, family, slow_loop=slow_loop_from(slow_loop), counts_per_rev=_fraction(counts_per_rev),
                firmware=firmware, location=Location(source) if source else None)
    _render_explanation(e, values, source, html, as_json)


def _project_values(project: str, drive_name: str | None, allow_errors: bool,
                    family: str) -> tuple[dict[tuple[int, int], int], str]:
    """(what the project's drive holds after its startup list, the family to explain it in: the drive's, unless
    --profile was given)."""
    from ecattool.project.machine import load_machine
    from ecattool.scaling.explain import FACTOR_INDICES, explain_family

    chosen = load_machine(project).slave_to_act_on(drive_name, "explain", allow_errors=allow_errors)
    if click.get_current_context().get_parameter_source("family") is click.core.ParameterSource.DEFAULT:
        family = explain_family(chosen.family)
    return chosen.object_values(FACTOR_INDICES), family


def _assignments(assignments: tuple[str, ...]) -> dict[tuple[int, int], int]:
    """The INDEX:SUB=VALUE arguments as object values."""
    from ecattool.od.numbers import parse_address, parse_int

    values: dict[tuple[int, int], int] = {}
    for a in assignments:
        if "=" not in a:
            raise click.BadParameter(f"{a!r}: write INDEX:SUB=VALUE, e.g. 6093:01=2000", param_hint="ASSIGNMENTS")
        addr, val = a.split("=", 1)
        values[parse_address(addr)] = parse_int(val)
    return values


def _fraction(number: str | None) -> Fraction | None:
    from ecattool.od.numbers import parse_int

    return Fraction(parse_int(number)) if number else None


def _render_explanation(e: Explanation, values: dict[tuple[int, int], int], source: str | None, html: str | None,
                        as_json: bool) -> None:
    """The explanation as a page (--html), JSON or a table with its findings."""
    if html:
        from ecattool.report import scaling_html

        write_output(html, scaling_html(e, values, title=source or ""), (source,) if source else ())
        if html == "-":
            return
    if as_json:
        print_json(e.to_json())
        return
    con = console()
    t = table(f"{e.family} ({e.factor_set})", ["quantity", "meaning"])
    for q, m in e.lines:
        t.add_row(q, m)
    con.print(t)
    for f in e.findings:
        con.print(f"{f.severity.value}: {f.message} [{f.rule}]")


def _target_slave(spec: str, family: str, slave: int, firmware: str | None) -> SlaveTarget:
    """The drive at ``slave`` of ``spec`` (a bare 'sim' holds the family's drive), in PRE-OP; the target errors
    name the option they are about."""
    from ecattool.online.targets import open_slave
    from ecattool.scaling.explain import family_drives
    from ecattool.target.opener import SLAVE_TARGET_FORMS, parse_target

    try:
        devices = family_drives(family, firmware)
        if parse_target(spec).own_slaves and not devices:
            raise InputError("--target sim needs a built-in family (technosoft-ipos, hdt, controltechniques)")
        return open_slave(spec, devices, slave, reset_bus_given(), in_preop=True)
    except SelectionError as exc:
        if exc.message.startswith("unknown target"):
            raise click.BadParameter(f"use {SLAVE_TARGET_FORMS}", param_hint="--target") from None
        raise InputError(f"--slave {slave}: {exc.message}") from None


@scale.command("si", epilog="""\b
Examples:
  ecattool scale si mm rpm deg/s^2
  ecattool scale si 0xFD010100 0x00B44700 --json""")
@click.argument("items", nargs=-1, required=True)
@json_option
def si_cmd(items: tuple[str, ...], as_json: bool) -> None:
    """Encode units as CiA-303-2 SI unit words (60A8h–60ABh), or decode words back to units."""
    from ecattool.od.numbers import parse_int
    from ecattool.scaling import decode_si_unit, encode_si_unit

    rows = []
    for item in items:
        if item[:2].lower() in ("0x", "#x") or item.isdigit():
            word = parse_int(item)
            rows.append({"word": f"0x{word:08X}", "unit": decode_si_unit(word)})
        else:
            rows.append({"word": f"0x{encode_si_unit(item):08X}", "unit": item})
    if as_json:
        print_json(rows)
        return
    t = table(None, ["unit", "SI word"])
    for r in rows:
        t.add_row(r["unit"], r["word"])
    console().print(t)
