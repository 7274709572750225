"""Hostile XML is refused with a clear error, in bounded time and memory, through esi.load and the CLI."""

from __future__ import annotations

import subprocess
import sys

import pytest

from ecattool.errors import XmlSecurityError
from ecattool.esi import load, load_bytes, validate

ENTITIES = (b'<?xml version="1.0"?>\n<!DOCTYPE EtherCATInfo [<!ENTITY v "Vendor">]>\n'
            b"<EtherCATInfo><Vendor><Id>1</Id><Name>&v;</Name></Vendor><Descriptions/></EtherCATInfo>")
EXTERNAL = (b'<?xml version="1.0"?>\n<!DOCTYPE EtherCATInfo [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
            b"<EtherCATInfo><Vendor><Id>1</Id><Name>&x;</Name></Vendor><Descriptions/></EtherCATInfo>")
LAUGHS = (b'<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
          + b"".join(f'<!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">'.encode() for i in range(1, 10))
          + b"]>\n<EtherCATInfo><Vendor><Id>1</Id><Name>&lol9;</Name></Vendor></EtherCATInfo>")
PLAIN_DOCTYPE = b'<?xml version="1.0"?>\n<!DOCTYPE EtherCATInfo SYSTEM "http://example.com/esi.dtd">\n<EtherCATInfo/>'

CASES = {"entities": ENTITIES, "external": EXTERNAL, "billion-laughs": LAUGHS, "doctype": PLAIN_DOCTYPE}


@pytest.mark.parametrize("name", sorted(CASES))
def test_load_refuses(name, tmp_path):
    with pytest.raises(XmlSecurityError) as info:
        load_bytes(CASES[name], f"{name}.xml")
    assert info.value.location.file == f"{name}.xml" and info.value.location.line == 2
    path = tmp_path / f"{name}.xml"
    path.write_bytes(CASES[name])
    with pytest.raises(XmlSecurityError):
        load(path)
    with pytest.raises(XmlSecurityError):
        validate(path)


@pytest.mark.parametrize("name", ["entities", "external", "billion-laughs"])
def test_cli_refuses_with_one_line(name, tmp_path):
    path = tmp_path / f"{name}.xml"
    path.write_bytes(CASES[name])
    for cmd in (["devices"], ["show"], ["validate"]):
        out = subprocess.run([sys.executable, "-m", "ecattool", "esi", *cmd, str(path)], capture_output=True, text=True,
                             timeout=60)
        assert out.returncode == 1, (cmd, out.stderr)
        lines = out.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in out.stderr
        assert f"{name}.xml:2" in lines[0] and "refused" in lines[0]
        assert "root:" not in out.stdout  # nothing of /etc/passwd leaks
