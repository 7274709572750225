"""Validation of ESI files: the ETG XSD schemas (not shipped; give their directory) plus the structural checks."""

from __future__ import annotations

from pathlib import Path

from ecattool.errors import EcatToolError, InputError, Location, XmlSecurityError
from ecattool.findings import Finding, Severity

#: root element → schema file name
SCHEMAS = {"EtherCATInfo": "EtherCATInfo.xsd", "EtherCATModule": "EtherCATModule.xsd", "EtherCATDict": "EtherCATDict.xsd"}


def _schema(path: Path):  # type: ignore[no-untyped-def]
    from lxml import etree

    from ecattool.fileio import read_bytes
    from ecattool.xmlsafe import MAX_XML_BYTES, check_xml_bytes

    data = read_bytes(path, MAX_XML_BYTES)
    check_xml_bytes(data, str(path))
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False)
    try:
        doc = etree.fromstring(data, parser, base_url=str(path.resolve()))
        return etree.XMLSchema(etree.ElementTree(doc))
    except (etree.XMLSyntaxError, etree.XMLSchemaParseError) as exc:
        raise InputError(f"schema does not load: {exc}", Location(str(path))) from None


def schema_findings(tree, source: str, schema_dir: str | Path) -> list[Finding]:  # type: ignore[no-untyped-def]
    root = tree.getroot()
    tag = root.tag if isinstance(root.tag, str) else ""
    name = SCHEMAS.get(tag)
    if name is None:
        raise InputError(f"root element <{tag}> has no ETG schema (expected one of {', '.join(SCHEMAS)})", Location(source, root.sourceline))
    d = Path(schema_dir)
    path = d / name
    if not path.is_file():
        raise InputError(f"schema directory has no {name} (needed for a <{tag}> root)", Location(str(d)))
    schema = _schema(path)
    schema.validate(tree)
    out = []
    for err in schema.error_log:
        out.append(Finding("esi-xsd", Severity.ERROR, err.message, Location(source, err.line or None, err.column or None),
                           {"schema": str(path)}))
    return out


def validate(path: str | Path, schema_dir: str | Path | None = None) -> list[Finding]:
    """All findings for one ESI file: XSD errors (with ``schema_dir``), reader warnings and structural checks.

    A file that is not well-formed XML (or refused for security) raises :class:`InputError`; a file that is
    well-formed but cannot be modelled gives an ``esi-load`` error finding.
    """
    from ecattool.esi.checks import check_structure
    from ecattool.esi.reader import _read, load_bytes
    from ecattool.xmlsafe import parse_xml

    p = Path(path)
    data = _read(p)
    findings: list[Finding] = []
    from ecattool.esi.eds import load_eds_bytes, looks_like_eds

    if looks_like_eds(data):  # a CANopen EDS/DCF: read by python-canopen, no ETG schema applies
        eds = load_eds_bytes(data, str(p))
        if schema_dir is not None:
            findings.append(Finding("esi-xsd", Severity.INFO, "a CANopen EDS/DCF has no ETG schema: XSD not checked",
                                    Location(str(p))))
        return [*findings, *eds.warnings, *check_structure(eds)]
    esi = None
    try:
        esi = load_bytes(data, str(p), p.parent)
        structural = check_structure(esi)
        materialize(esi)
    except XmlSecurityError:
        raise
    except EcatToolError as exc:
        if "not well-formed" in exc.message:
            raise
        findings.append(Finding("esi-load", Severity.ERROR, exc.message, exc.location))
    if schema_dir is not None:
        try:
            tree = parse_xml(data, str(p))
        except InputError as exc:
            findings.append(Finding("esi-xsd", Severity.ERROR, f"not checked against the schema: {exc.message}", exc.location))
        else:
            findings[:0] = schema_findings(tree, str(p), schema_dir)
    if esi is not None:
        findings.extend(esi.warnings)
        findings.extend(structural)
    return findings


def materialize(esi) -> int:  # type: ignore[no-untyped-def]
    """Build every (lazily read) dictionary of ``esi``; returns the number of objects."""
    n = len(esi.dictionary) if esi.dictionary is not None else 0
    for dev in esi.devices:
        n += len(dev.dictionary)
        for m in dev.modules:
            n += len(m.dictionary)
    for m in esi.modules:
        n += len(m.dictionary)
    return n
