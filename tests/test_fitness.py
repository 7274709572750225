"""Fitness tests: each "one place" claim of the architecture (issue 36.5) as a check over the package's source,
beside tests/test_layering.py (which holds the import layers). Each walks the syntax trees of ``ecattool/`` and
fails naming the file and line that breaks its claim:

* only the resolver (``profiles/running.py``) completes a device: ``plug_default_modules(``/``complete_generic(``
  are called nowhere else (``complete_generic`` composes ``plug_default_modules`` where both are defined);
* the AL status codes are defined once (``abort.AlStatus`` beside its texts): no other ``AL_…`` constant, text
  table, literal default or ``al_status=`` literal argument holds one;
* the CiA-402 statusword masks, state bits and controlword commands are defined once (``od/cia402.py``);
* the typed ``FamilyRules`` is read by field, never with ``getattr(rules, "…", default)``;
* every SDO upload through a master outside the simulator gives its size bound (issue 37.1);
* each master has one adapter module (issue 36.3): only ``target/pysoem.py`` imports pysoem or touches its
  master's and slaves' objects, only ``target/kickcat.py`` KickCAT's; only the opener constructs a target;
* an import inside a function defers something (issue 36.4: library imports at module level): every module it
  loads is one its module has not loaded already; the lazy ones left keep a command's start lean or an optional
  dependency optional;
* no ``family == "…"`` decision outside the built-in families (``profiles/``) and the simulator's family modules,
  but for today's remaining places, listed below with their counts: the list may only shrink;
* the CLI is thin (issue 36.4): no function in ``cli/`` runs longer than :data:`CLI_BODY_LINES` lines, but for the
  few declaring ones listed with their reason; a command reads its flags, builds the model, calls
  the library and renders, and the work between lives in the packages.
"""

from __future__ import annotations

import ast
import functools
import sys
from collections.abc import Iterator
from pathlib import Path

from ecattool.abort import AlStatus
from ecattool.profiles import running
from tests.test_layering import PKG, _modules

ROOT = PKG.parent


@functools.cache
def _trees() -> dict[str, ast.Module]:
    """Package-relative path (``sim/slave.py``) → syntax tree, for every module of ``ecattool/``."""
    return {path.relative_to(PKG).as_posix(): ast.parse(path.read_text(encoding="utf-8"), str(path))
            for path in _modules().values() if path is not None}


def _where(rel: str, node: ast.AST) -> str:
    return f"ecattool/{rel}:{getattr(node, 'lineno', '?')}"


def _called_name(node: ast.Call) -> str | None:
    f = node.func
    return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None


def _functions(tree: ast.AST) -> Iterator[tuple[str, ast.AST]]:
    """(enclosing function name or "", node) for every node of ``tree``."""
    def walk(node: ast.AST, owner: str) -> Iterator[tuple[str, ast.AST]]:
        for child in ast.iter_child_nodes(node):
            name = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else owner
            yield name, child
            yield from walk(child, name)
    yield from walk(tree, "")


# --- only the resolver completes a device ----------------------------------------------------------------------

#: (module, enclosing function) allowed to call each completion function
COMPLETERS = {
    "complete_generic": {("profiles/running.py", "as_running")},
    # the rule composes: completing a device plugs its default modules first
    "plug_default_modules": {("profiles/generic.py", "complete_generic")},
}


def completion_calls(trees: dict[str, ast.Module]) -> list[str]:
    found = []
    for rel, tree in trees.items():
        for owner, node in _functions(tree):
            if isinstance(node, ast.Call) and _called_name(node) in COMPLETERS:
                name = _called_name(node)
                assert name is not None
                if (rel, owner) not in COMPLETERS[name]:
                    found.append(f"{_where(rel, node)} calls {name}() in {owner or 'module level'}")
    return found


def test_only_the_resolver_completes_a_device() -> None:
    found = completion_calls(_trees())
    assert not found, ("a device is completed outside the resolver; take it from ecattool.profiles.running "
                       "(as_running / resolve_device) instead:\n" + "\n".join(found))
    # and the resolver does call it (else the allowance above is stale)
    assert not completion_calls({"profiles/running.py": _trees()["profiles/running.py"]})
    assert any(isinstance(n, ast.Call) and _called_name(n) == "complete_generic"
               for n in ast.walk(_trees()["profiles/running.py"]))


# --- AL status codes defined once ------------------------------------------------------------------------------

AL_CODES = frozenset(int(c) for c in AlStatus)


def _int(node: ast.AST | None) -> int | None:
    return node.value if isinstance(node, ast.Constant) and type(node.value) is int else None


def al_code_definitions(trees: dict[str, ast.Module]) -> list[str]:
    found = []
    for rel, tree in trees.items():
        if rel == "abort.py":
            continue
        for node in ast.walk(tree):
            if isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = [t.id for t in targets if isinstance(t, ast.Name)]
                if any(n.lstrip("_").startswith("AL_") for n in names) and _int(node.value) in AL_CODES:
                    found.append(f"{_where(rel, node)}: {names[0]} = 0x{_int(node.value):04X}")
            elif isinstance(node, ast.keyword) and node.arg and "al_status" in node.arg and _int(node.value) in AL_CODES:
                found.append(f"{_where(rel, node.value)}: {node.arg}=0x{_int(node.value):04X}")
            elif isinstance(node, ast.arguments):
                params = [*node.posonlyargs, *node.args]
                defaults = [*([None] * (len(params) - len(node.defaults))), *node.defaults]
                pairs = [*zip(params, defaults), *zip(node.kwonlyargs, node.kw_defaults)]
                for arg, default in pairs:
                    if "al_status" in arg.arg and _int(default) is not None:
                        found.append(f"{_where(rel, arg)}: parameter {arg.arg} defaults to a literal code")
            elif isinstance(node, ast.Dict) and len(node.keys) >= 3:
                keys = [_int(k) for k in node.keys]
                if (all(k in AL_CODES for k in keys) and any(k is not None and k >= 0x11 for k in keys)
                        and all(isinstance(v, ast.Constant) and isinstance(v.value, str) for v in node.values)):
                    found.append(f"{_where(rel, node)}: a table of AL status texts")
    return found


def test_al_status_codes_are_defined_once() -> None:
    found = al_code_definitions(_trees())
    assert not found, "AL status codes defined outside ecattool.abort (use AlStatus):\n" + "\n".join(found)


# --- CiA-402 statusword masks defined once ---------------------------------------------------------------------

STATE_MASKS = {0x4F, 0x6F}
#: statusword bits of READY TO SWITCH ON, SWITCHED ON and OPERATION ENABLED: a dict holding them is a state table
STATE_BITS = {0x21, 0x23, 0x27}
#: controlword commands by (mask, value) as the state machine reads them
COMMAND_MASKS = {(0x07, 0x06), (0x0F, 0x07), (0x0F, 0x0F), (0x06, 0x02)}


def cia402_definitions(trees: dict[str, ast.Module]) -> list[str]:
    found = []
    for rel, tree in trees.items():
        if rel == "od/cia402.py":
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitAnd):
                if _int(node.left) in STATE_MASKS or _int(node.right) in STATE_MASKS:
                    found.append(f"{_where(rel, node)}: a statusword state mask")
            elif isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], ast.Eq):
                left, right = node.left, node.comparators[0]
                if isinstance(left, ast.BinOp) and isinstance(left.op, ast.BitAnd):
                    pair = (_int(left.right), _int(right))
                    if pair in COMMAND_MASKS:
                        found.append(f"{_where(rel, node)}: a controlword command mask")
            elif isinstance(node, ast.Dict):
                values = {_int(v) for v in node.values}
                if STATE_BITS <= values:
                    found.append(f"{_where(rel, node)}: a table of CiA-402 state bits")
            elif isinstance(node, ast.ClassDef):
                members = {t.id for s in node.body if isinstance(s, ast.Assign) for t in s.targets
                           if isinstance(t, ast.Name)}
                if {"SWITCH_ON_DISABLED", "OPERATION_ENABLED", "FAULT_REACTION"} <= members:
                    found.append(f"{_where(rel, node)}: a second CiA-402 state enumeration ({node.name})")
    return found


def test_statusword_masks_and_states_are_defined_once() -> None:
    found = cia402_definitions(_trees())
    assert not found, "CiA-402 definitions outside ecattool.od.cia402 (import them from there):\n" + "\n".join(found)


# --- FamilyRules is read by field ------------------------------------------------------------------------------

def _names_rules(node: ast.AST) -> bool:
    name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""
    return name == "rules" or name.endswith("_rules")


def rules_getattr(trees: dict[str, ast.Module]) -> list[str]:
    return [f"{_where(rel, node)}: getattr({ast.unparse(node.args[0])}, …)"
            for rel, tree in trees.items() for node in ast.walk(tree)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr"
            and node.args and _names_rules(node.args[0])]


def test_family_rules_are_read_by_field() -> None:
    found = rules_getattr(_trees())
    assert not found, ("getattr on the typed FamilyRules: read the field ((rules or NO_RULES).field where the "
                       "rules may be missing):\n" + "\n".join(found))


# --- no family == outside the families ------------------------------------------------------------------------

#: where a decision by family name belongs: the built-in families and the simulator's family modules
FAMILY_MODULES = ("profiles/", "sim/drive/family.py", "sim/drive/behaviour.py")
#: today's other places that decide by family name, and how many comparisons each holds. The list may only
#: shrink: move a rule into FamilyRules (or the family module) and lower or remove its count here.
FAMILY_COMPARISONS_LEFT = {
    "pdo/check.py": 1,
    "project/skeleton.py": 1,
    "project/steps.py": 1,
    "scaling/compute.py": 7,
    "scaling/explain.py": 3,
}


def _names_family(node: ast.AST) -> bool:
    name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""
    return name in ("family", "fam")


def _is_names(node: ast.AST) -> bool:
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str)
    return isinstance(node, (ast.Tuple, ast.List, ast.Set)) and bool(node.elts) and all(_is_names(e) for e in node.elts)


def family_comparisons(trees: dict[str, ast.Module]) -> dict[str, list[str]]:
    """Module → the comparisons of a family name with a literal name (==, !=, in, not in) it holds."""
    found: dict[str, list[str]] = {}
    for rel, tree in trees.items():
        if rel.startswith(FAMILY_MODULES):
            continue
        for node in ast.walk(tree):
            if not isinstance(node, ast.Compare) or len(node.ops) != 1:
                continue
            if not isinstance(node.ops[0], (ast.Eq, ast.NotEq, ast.In, ast.NotIn)):
                continue
            left, right = node.left, node.comparators[0]
            if (_names_family(left) and _is_names(right)) or (_names_family(right) and _is_names(left)):
                found.setdefault(rel, []).append(f"{_where(rel, node)}: {ast.unparse(node)}")
    return found


def test_no_new_family_name_decisions() -> None:
    found = family_comparisons(_trees())
    grown = [f"{rel}: {len(lines)} (allowed {FAMILY_COMPARISONS_LEFT.get(rel, 0)})\n  " + "\n  ".join(lines)
             for rel, lines in sorted(found.items()) if len(lines) > FAMILY_COMPARISONS_LEFT.get(rel, 0)]
    assert not grown, ("a decision by family name outside profiles/ and the family modules: make it FamilyRules "
                       "data (or move it into the family module):\n" + "\n".join(grown))


# --- every upload through a master is bounded -------------------------------------------------------------------

def unbounded_uploads(trees: dict[str, ast.Module]) -> list[str]:
    """The ``sdo_upload(…)`` calls outside the simulator that give no ``size`` (issue 37.1: never ask a master for
    more than the object can be; the simulator's own calls read its own store)."""
    return [f"{_where(rel, node)}: {ast.unparse(node)[:80]}" for rel, tree in trees.items()
            if not rel.startswith("sim/") for node in ast.walk(tree)
            if isinstance(node, ast.Call) and _called_name(node) == "sdo_upload"
            and "size" not in {k.arg for k in node.keywords} and len(node.args) < 4]


def test_every_upload_through_a_master_is_bounded_by_its_object() -> None:
    found = unbounded_uploads(_trees())
    assert not found, "an SDO upload without its size bound (pass size=, the object's type's size):\n" + "\n".join(found)


# --- the simulated drive is composed of parts (issue 33, item 1) ----------------------------------------------

def drive_part_inheritance(trees: dict[str, ast.Module]) -> list[str]:
    """The classes of sim/drive/ that inherit another class of sim/drive/ (the drive's parts are objects the
    drive holds and wires together, not mixins over a shared core)."""
    drive_modules = {rel: tree for rel, tree in trees.items() if rel.startswith("sim/drive/")}
    ours = {node.name for tree in drive_modules.values() for node in ast.walk(tree) if isinstance(node, ast.ClassDef)}
    return [f"{_where(rel, node)}: class {node.name}({', '.join(ast.unparse(b) for b in node.bases)})"
            for rel, tree in drive_modules.items() for node in ast.walk(tree) if isinstance(node, ast.ClassDef)
            for base in node.bases
            if (base.id if isinstance(base, ast.Name) else base.attr if isinstance(base, ast.Attribute) else "") in ours]


def test_the_drive_is_composed_of_parts_not_mixins() -> None:
    from ecattool.sim.drive import Drive

    assert Drive.__mro__ == (Drive, object), f"Drive inherits {Drive.__mro__[1:-1]}: hold the part instead"
    found = drive_part_inheritance(_trees())
    assert not found, ("a class of the drive application inherits another of its parts: give it the part (or the "
                       "collaborator it needs) at construction instead:\n" + "\n".join(found))
    # the parts are there, one object per concern
    drive = Drive.from_profile("hdt")
    parts = ("objects", "event_log", "family_part", "pdo", "sdo", "process_data", "state_machine", "motion",
             "injection", "nonvolatile")
    assert len({id(getattr(drive, name)) for name in parts}) == len(parts)


# --- one target opener, DC resolved once (the claims two tests of tests/project/test_machine.py are named after) ----------

#: the classes that are slave targets, and the constructor methods they have
TARGET_CLASSES = ("SimTarget", "PysoemTarget", "KickcatTarget")
#: where a target may be constructed: the opener (the simulator; a real master for a live bus, which
#: ``online.targets.open_bus`` runs in its child process), and the pysoem target the opener starts in its child
#: process for the commands that act on slaves (target/isolated.py, issue 37.1)
TARGET_CONSTRUCTORS = {"target/opener.py": 3, "target/isolated.py": 1}


def target_constructions(trees: dict[str, ast.Module]) -> dict[str, list[str]]:
    """Module → the calls that construct a slave target (``SimTarget(…)``, ``SimTarget.from_devices(…)``,
    ``PysoemTarget(…)``, ``KickcatTarget(…)``) it holds, the classes' own modules left out."""
    found: dict[str, list[str]] = {}
    for rel, tree in trees.items():
        if rel in ("target/sim.py", "target/pysoem.py", "target/kickcat.py"):
            continue
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            named = (f.id if isinstance(f, ast.Name) else f.value.id
                     if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) else "")
            if named in TARGET_CLASSES:
                found.setdefault(rel, []).append(f"{_where(rel, node)}: {ast.unparse(node.func)}(…)")
    return found


def calls_of(trees: dict[str, ast.Module], name: str) -> list[str]:
    """Where the package calls the function ``name`` (by its bare or dotted name)."""
    return [f"{_where(rel, node)} in {owner or 'module level'}" for rel, tree in trees.items()
            for owner, node in _functions(tree) if isinstance(node, ast.Call) and _called_name(node) == name]


# --- each master has one adapter module (issue 36.3) ------------------------------------------------------------

#: each master binding and its one adapter module: only it imports the binding
ADAPTERS = {"pysoem": "target/pysoem.py", "kickcat": "target/kickcat.py"}
#: what only a binding's own objects have, by binding: SOEM's master and slave objects through pysoem (the SII
#: EEPROM, SDO Information's ``od``, the SDO calls, the state machine, DC, process data, the startup hook) and
#: KickCAT's bus, link and mailbox. An attribute of ``self`` does not count (``self.od``: a checker's dictionary)
BINDING_ATTRIBUTES = {
    "pysoem": frozenset({"eeprom_read", "eeprom_write", "od", "sdo_read", "sdo_write", "add_emergency_callback",
                         "state_check", "write_state", "config_init", "config_map", "config_dc", "send_processdata",
                         "receive_processdata", "config_func", "manual_state_change", "always_release_gil"}),
    "kickcat": frozenset({"read_sdo", "write_sdo", "process_mailboxes", "create_link", "get_state", "set_timeout",
                          "create_mapping"}),
}


def binding_uses(trees: dict[str, ast.Module]) -> list[str]:
    """Where a module other than a binding's adapter imports the binding (``import pysoem``, ``from kickcat…``) or
    uses what only the binding's objects have (:data:`BINDING_ATTRIBUTES`)."""
    found = []
    for rel, tree in trees.items():
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) or (isinstance(node, ast.ImportFrom) and not node.level):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
                for name in names:
                    binding = name.split(".")[0]
                    if binding in ADAPTERS and rel != ADAPTERS[binding]:
                        found.append(f"{_where(rel, node)}: import {name} (only {ADAPTERS[binding]} may)")
            elif isinstance(node, ast.Attribute) and not (isinstance(node.value, ast.Name) and node.value.id == "self"):
                for binding, attributes in BINDING_ATTRIBUTES.items():
                    if node.attr in attributes and rel != ADAPTERS[binding]:
                        found.append(f"{_where(rel, node)}: {ast.unparse(node)} ({binding}'s object: only "
                                      f"{ADAPTERS[binding]} may)")
    return found


def test_each_master_has_one_adapter_module() -> None:
    found = binding_uses(_trees())
    assert not found, ("a master binding reached outside its adapter module (put it into the adapter, the rest of the "
                       "package talks to target.base.LiveSlave):\n" + "\n".join(found))


def test_the_adapters_are_the_ones_that_reach_their_bindings() -> None:
    """The check above looks for the right things: each adapter holds its binding's import and objects' names."""
    for binding, adapter in ADAPTERS.items():
        alone = {rel: tree for rel, tree in _trees().items() if rel == adapter}
        moved = {"elsewhere.py": tree for tree in alone.values()}
        assert not binding_uses(alone), adapter
        uses = binding_uses(moved)
        assert any(f"import {binding}" in u for u in uses), (adapter, uses)
        assert any(a in u for u in uses for a in BINDING_ATTRIBUTES[binding]), (adapter, uses)


# --- the CLI is thin (issue 36.4) --------------------------------------------------------------------------------

#: how long a function of ``cli/`` may be, in lines of its body without the docstring (a command's docstring is its
#: --help): room for flags → model → action → render; what needs more is domain work for a package, or rendering
#: for a ``_render_…`` helper (issue 36.4: "no cli/ function longer than about 20 lines does domain work")
CLI_BODY_LINES = 20
#: the longer ones that remain, (module, function) → why it may: none does domain work. The list may only shrink
#: (an entry whose function got shorter or went away fails below, so that the list stays true)
CLI_LONG_ALLOWED = {
    ("cli/scale.py", "_mechanics_options"): "declares the mechanics flags (a list of click options), no logic",
    ("cli/map.py", "_device_options"): "declares the device and mapping flags (a list of click options), no logic",
    ("cli/__init__.py", "main"): "the entry point: one except clause per kind of error, each its message and exit code",
}


def _body_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    body = node.body
    if (len(body) > 1 and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
            and isinstance(body[0].value.value, str)):
        body = body[1:]  # a click command's docstring is its --help text, not code
    return (node.end_lineno or node.lineno) - body[0].lineno + 1


def long_cli_functions(trees: dict[str, ast.Module]) -> dict[tuple[str, str], str]:
    """(module, function) → where and how long, for every function of ``cli/`` longer than :data:`CLI_BODY_LINES`
    (nested functions counted on their own and within their enclosing one)."""
    found = {}
    for rel, tree in trees.items():
        if not rel.startswith("cli/"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _body_lines(node) > CLI_BODY_LINES:
                found[(rel, node.name)] = f"{_where(rel, node)}: {node.name}() has {_body_lines(node)} lines"
    return found


def test_the_cli_is_thin() -> None:
    found = long_cli_functions(_trees())
    grown = [where for key, where in sorted(found.items()) if key not in CLI_LONG_ALLOWED]
    assert not grown, (f"a cli/ function longer than {CLI_BODY_LINES} lines: move its domain work into the package "
                       "it belongs to (a typed library function), and its printing into _render_… helpers:\n"
                       + "\n".join(grown))
    stale = [f"{rel} {name}: {why}" for (rel, name), why in CLI_LONG_ALLOWED.items()
             if (rel, name) not in found]
    assert not stale, "no longer long (or gone): remove from CLI_LONG_ALLOWED:\n" + "\n".join(stale)


def test_the_thin_cli_check_finds_a_long_function() -> None:
    """The check above looks at what it should: a command that assembles its inputs in 30 lines is found, one
    of 20 lines with a docstring of any length is not."""
    def command(name: str, lines: int, doc_lines: int = 1) -> str:
        doc = '    """' + "\n    ".join(["help"] * doc_lines) + '"""\n'
        return f"def {name}(a):\n" + doc + "".join(f"    a = a + {i}\n" for i in range(lines))
    tree = ast.parse(command("assemble_cmd", 30) + command("render_cmd", 20, doc_lines=40))
    found = long_cli_functions({"cli/planted.py": tree, "scaling/planted.py": tree})
    assert list(found) == [("cli/planted.py", "assemble_cmd")], found
    assert found[("cli/planted.py", "assemble_cmd")] == "ecattool/cli/planted.py:1: assemble_cmd() has 30 lines"


# --- device flags build a one-slave machine (issue 36.4) --------------------------------------------------------

#: what resolves a device outside a machine: the resolver's functions (its ``__all__`` but the type it marks
#: devices with) and the simulator's constructors that call it
RESOLVER_CALLS = frozenset(n for n in running.__all__ if n != "RunningDevice") | {"from_esi", "from_profile"}


def cli_resolver_uses(trees: dict[str, ast.Module]) -> list[str]:
    """Where a module of ``cli/`` calls the resolver, imports one of its functions, or imports the module itself
    (``running.resolve_device(…)`` would be a call through it)."""
    found = []
    for rel, tree in trees.items():
        if not rel.startswith("cli/"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and _called_name(node) in RESOLVER_CALLS:
                found.append(f"{_where(rel, node)} calls {_called_name(node)}()")
            elif isinstance(node, ast.ImportFrom) and node.module == "ecattool.profiles.running":
                found.extend(f"{_where(rel, node)} imports {a.name} from the resolver" for a in node.names
                             if a.name in RESOLVER_CALLS or a.name == "*")
            elif isinstance(node, ast.ImportFrom) and node.module == "ecattool.profiles":
                found.extend(f"{_where(rel, node)} imports the resolver module" for a in node.names
                             if a.name == "running")
            elif isinstance(node, ast.Import):
                found.extend(f"{_where(rel, node)} imports the resolver module" for a in node.names
                             if a.name == "ecattool.profiles.running")
    return found


def test_device_flags_build_a_machine_not_the_resolver() -> None:
    found = cli_resolver_uses(_trees())
    assert not found, ("cli/ resolves a device itself; build the one-slave machine the flags name instead "
                       "(ecattool.project.machine.Machine.from_device_flags) and act on its slaves[0]:\n"
                       + "\n".join(found))


def test_the_resolver_check_finds_a_planted_call() -> None:
    """The check above looks at what it should: each way a command could reach the resolver is found, the type
    import and the machine are not."""
    planted = ast.parse(
        "from ecattool.profiles.running import RunningDevice, device_from_file\n"
        "from ecattool.profiles import running\n"
        "import ecattool.profiles.running\n"
        "def cmd(esi):\n"
        "    running.resolve_device(esi)\n"
        "    Drive.from_esi(esi)\n"
        "    return Machine.from_device_flags(esi=esi).slaves[0]\n")
    found = cli_resolver_uses({"cli/planted.py": planted, "project/planted.py": planted})
    assert found == ["ecattool/cli/planted.py:1 imports device_from_file from the resolver",
                     "ecattool/cli/planted.py:2 imports the resolver module",
                     "ecattool/cli/planted.py:3 imports the resolver module",
                     "ecattool/cli/planted.py:5 calls resolve_device()",
                     "ecattool/cli/planted.py:6 calls from_esi()"], found


# --- a function-level import defers something ------------------------------------------------------------------

def _placement(node: ast.AST, parents: dict[ast.AST, ast.AST]) -> str | None:
    """"module" for an import run when its module is (top level, not under ``if TYPE_CHECKING:`` or ``try:``),
    "function" for one inside a function (not guarded by ``try:``: an optional dependency), else None."""
    inside, parent = "module", parents.get(node)
    while parent is not None:
        if isinstance(parent, ast.Try) or (isinstance(parent, ast.If) and "TYPE_CHECKING" in ast.unparse(parent.test)):
            return None
        if isinstance(parent, (ast.FunctionDef, ast.AsyncFunctionDef)):
            inside = "function"
        parent = parents.get(parent)
    return inside


def _targets(node: ast.Import | ast.ImportFrom, module: str, is_package: bool, mods: dict[str, Path | None]) -> list[str]:
    """The modules an import statement loads (``from a import b``: ``a.b`` where that is a module, else ``a``)."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    package = module if is_package else module.rpartition(".")[0]
    source = node.module or ""
    if node.level:
        source = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1] + ([source] if source else []))
    return [f"{source}.{a.name}" if f"{source}.{a.name}" in mods else source for a in node.names]


def _with_packages(name: str) -> set[str]:
    """``a.b.c`` and the packages Python imports before it (``a``, ``a.b``)."""
    parts = name.split(".")
    return {".".join(parts[:i]) for i in range(1, len(parts) + 1)}


def _imports_by_placement() -> dict[str, dict[str, list[tuple[ast.AST, list[str]]]]]:
    """Module → {"module"/"function": [(import statement, the modules it loads)], "file": [(None, [its path])]}."""
    mods = _modules()
    out: dict[str, dict[str, list[tuple[ast.AST, list[str]]]]] = {}
    for name, path in mods.items():
        if path is None:
            continue
        tree = _trees()[path.relative_to(PKG).as_posix()]
        parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
        rel = path.relative_to(PKG).as_posix()
        placed: dict[str, list[tuple[ast.AST, list[str]]]] = {"module": [], "function": [], "file": [(tree, [rel])]}
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                where = _placement(node, parents)
                if where is not None:
                    placed[where].append((node, _targets(node, name, path.name == "__init__.py", mods)))
        out[name] = placed
    return out


def imports_that_defer_nothing() -> list[str]:
    """The imports inside functions whose every module the enclosing module has already loaded when it was
    imported (its module-level imports, followed through ecattool, with the packages Python imports first): such
    an import keeps nothing off a start-up path, so it belongs at module level (issue 36.4). A lazy import that
    loads something new stays: a lean command path, an optional dependency, the scaling package only for a drive
    with a ``scaling:`` section."""
    placed = _imports_by_placement()

    @functools.cache
    def loaded(module: str) -> frozenset[str]:
        seen: set[str] = set()
        todo = [module]
        while todo:
            current = todo.pop()
            if current in seen:
                continue
            seen.add(current)
            todo.extend(_with_packages(current) - {current})
            for _, targets in placed.get(current, {}).get("module", []):
                for target in targets:
                    todo.extend(_with_packages(target))
        return frozenset(seen)

    std = sys.stdlib_module_names
    found = []
    for module, by_place in placed.items():
        for node, targets in by_place["function"]:
            if all(t.split(".")[0] in std or t.startswith("ecattool") for t in targets) \
                    and all(t in loaded(module) and t != module for t in targets):
                found.append(f"{_where(by_place['file'][0][1][0], node)}: {ast.unparse(node)}")
    return found


def test_a_function_level_import_defers_something() -> None:
    found = imports_that_defer_nothing()
    assert not found, ("imports inside a function whose modules are loaded at module level already: they defer "
                       "nothing, import them at the top of the module:\n  " + "\n  ".join(found))
