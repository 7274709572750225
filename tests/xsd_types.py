"""The typed attributes and elements of the ETG.2000 XSDs, read from the schema files themselves (tests only).

:func:`typed_paths` walks the element declarations from a root (``EtherCATInfo``, ``EtherCATModule``,
``EtherCATDict``) through named and anonymous complex types, ``xs:extension`` bases and ``xs:include``\\ d
files, and lists every attribute or simple-content element whose type is a number, boolean or hex binary:
``("Device/Sm@Enable", "HexDecValue")``, ``("Device/RxPdo/Entry/BitLen", "xs:int")``. Paths start below the
root's container elements (``Descriptions/Devices``, ``Descriptions/Modules``, ``Modules``, ``Dictionary``'s
parent), so that the same path names a device's element in every root.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from lxml import etree

XS = "{http://www.w3.org/2001/XMLSchema}"
#: the schema types the reader must read by type (HexDecValue is ETG's; the rest are XML Schema's)
TYPED = frozenset({"HexDecValue", "xs:boolean", "xs:int", "xs:integer", "xs:hexBinary", "xs:float",
                   "xs:unsignedInt", "xs:unsignedShort", "xs:unsignedByte", "xs:short", "xs:byte", "xs:long",
                   "xs:double", "xs:decimal", "xs:nonNegativeInteger", "xs:positiveInteger"})
_PREFIXES = (("EtherCATInfo/Descriptions/Devices/", ""), ("EtherCATInfo/Descriptions/Modules/", ""),
             ("EtherCATInfo/Descriptions/", ""), ("EtherCATInfo/", ""), ("EtherCATModule/Modules/", ""),
             ("EtherCATModule/", ""), ("EtherCATDict/", ""))


def normalize(path: str) -> str:
    """A path from the root element, as :func:`typed_paths` names it: ``Device/…``, ``Module/…``, ``Vendor/…``,
    ``Groups/…``, and ``Dictionary/…`` for the dictionary of a device, a module or an EtherCATDict file."""
    cut = path.find("/Profile/Dictionary")
    if cut >= 0:
        return path[cut + len("/Profile/"):]
    for prefix, repl in _PREFIXES:
        if path.startswith(prefix):
            return repl + path[len(prefix):]
    return path


def _declarations(path: Path) -> tuple[dict[str, etree._Element], dict[str, etree._Element]]:
    types: dict[str, etree._Element] = {}
    elements: dict[str, etree._Element] = {}
    todo, seen = [path], set()
    while todo:
        p = todo.pop()
        if p in seen:
            continue
        seen.add(p)
        root = etree.parse(str(p)).getroot()
        for node in root:
            if node.tag in (XS + "complexType", XS + "simpleType"):
                types[node.get("name")] = node
            elif node.tag == XS + "element":
                elements[node.get("name")] = node
            elif node.tag in (XS + "include", XS + "import") and node.get("schemaLocation"):
                todo.append(p.parent / node.get("schemaLocation"))
    return types, elements


def _owner(node: etree._Element) -> etree._Element | None:
    """The nearest enclosing ``xs:complexType`` of ``node``."""
    p = node.getparent()
    while p is not None and p.tag != XS + "complexType":
        p = p.getparent()
    return p


@cache
def typed_paths(xsd: Path, root: str) -> tuple[tuple[str, str], ...]:
    """``(path, type)`` for every typed attribute (``…@Name``) and simple-content element under ``root``."""
    types, elements = _declarations(xsd)
    out: list[tuple[str, str]] = []

    def simple_base(node: etree._Element) -> str | None:
        t = node.get("type")
        if t is not None:
            return t
        st = node.find(XS + "simpleType")
        r = st.find(XS + "restriction") if st is not None else None
        return r.get("base") if r is not None else None

    def complex_type(ct: etree._Element, path: str, stack: tuple[str, ...]) -> None:
        for node in ct.iter(XS + "attribute", XS + "element", XS + "extension", XS + "restriction"):
            if _owner(node) is not ct:
                continue
            if node.tag == XS + "attribute":
                t = simple_base(node)
                if t in TYPED:
                    out.append((f"{path}@{node.get('name')}", t))
            elif node.tag in (XS + "extension", XS + "restriction"):
                base = node.get("base")
                if node.getparent().tag not in (XS + "simpleContent", XS + "complexContent"):
                    continue
                if base in TYPED:
                    out.append((path, base))
                elif base in types and stack.count(base) < 2:
                    complex_type(types[base], path, (*stack, base))
            else:
                element(node, path, stack)

    def element(el: etree._Element, parent: str, stack: tuple[str, ...]) -> None:
        ref = el.get("ref")
        if ref is not None:
            el = elements[ref]
        name = el.get("name")
        path = f"{parent}/{name}" if parent else name
        t = simple_base(el)
        if t in TYPED:
            out.append((path, t))
            return
        if t is not None and t in types:
            if stack.count(t) > 1:
                return
            decl = types[t]
            if decl.tag == XS + "simpleType":
                r = decl.find(XS + "restriction")
                if r is not None and r.get("base") in TYPED:
                    out.append((path, r.get("base")))
                return
            complex_type(decl, path, (*stack, t))
            return
        ct = el.find(XS + "complexType")
        if ct is not None:
            complex_type(ct, path, stack)

    element(elements[root], "", ())
    return tuple(dict.fromkeys((normalize(path), t) for path, t in out))
