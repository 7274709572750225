"""The fake pysoem of the test suite against the real module: every name, constant, signature, exception
attribute and property the fake pretends must exist in pysoem the same way. Skipped where pysoem is not
installed (it is an optional extra that compiles SOEM)."""

import inspect

import pytest

from tests.target import fake_pysoem

pysoem = pytest.importorskip("pysoem")

#: attributes of the fake that exist only for the tests (the simulated drive behind a slave, call records)
TEST_ONLY = {"drive", "pending_emergencies", "dc", "map_calls", "dc_configured", "opened", "clock", "sent_at", "sii",
             "sii_writes"}


def params(fn):
    return [(p.name, p.kind, p.default) for p in inspect.signature(fn).parameters.values()]


def public(cls):
    return {n: v for n, v in vars(cls).items() if not n.startswith("_") and n not in TEST_ONLY}


def test_names_and_constants():
    for name, value in fake_pysoem.public_surface().items():
        assert hasattr(pysoem, name), f"pysoem has no {name}"
        if isinstance(value, int):
            assert getattr(pysoem, name) == value, name


@pytest.mark.parametrize("name", ["SdoError", "Emergency", "MailboxError", "PacketError", "ConfigMapError",
                                  "WkcError", "NetworkInterfaceNotOpenError", "EepromError", "SdoInfoError"])
def test_exceptions(name):
    fake, real = getattr(fake_pysoem, name), getattr(pysoem, name)
    assert issubclass(real, Exception)
    assert params(fake.__init__) == params(real.__init__), name
    for attr, value in public(fake).items():
        assert isinstance(getattr(real, attr, None), type(value)), f"{name}.{attr}"


def _check_class(fake, real, instance=None):
    for name, value in public(fake).items():
        assert hasattr(real, name) or (instance is not None and hasattr(instance, name)), f"{real.__name__}.{name}"
        real_value = getattr(real, name, None)
        if isinstance(value, property):
            assert isinstance(real_value, property), f"{real.__name__}.{name} is not a property"
            assert (value.fset is None) == (real_value.fset is None), f"{real.__name__}.{name}: writable?"
        elif callable(value):
            assert params(value) == params(real_value), f"{real.__name__}.{name}"


def test_slave():
    _check_class(fake_pysoem.CdefSlave, pysoem.CdefSlave)


def test_master():
    fake_master = fake_pysoem.make_module([]).Master
    _check_class(fake_master, pysoem.Master, pysoem.Master())
    for attr in ("slaves", "manual_state_change", "context_initialized"):  # instance attributes of the fake
        assert hasattr(pysoem.Master(), attr), attr


def test_the_adapter_uses_only_real_names():
    """Every pysoem name the adapter reads from the module exists (state constants, exceptions)."""
    import ecattool.target.pysoem as adapter

    source = inspect.getsource(adapter)
    for name in fake_pysoem.public_surface():
        if f"mod.{name}" in source or f'"{name}"' in source:
            assert hasattr(pysoem, name), name


def test_the_od_objects_of_the_fake_have_the_real_entry_attributes():
    """``slave.od`` entries: the attributes ecattool.online reads exist on pysoem's CdefCoeObjectEntry."""
    for attr in vars(fake_pysoem.CoeObjectEntry("", 0, 0, 0)):
        assert hasattr(pysoem.CdefCoeObjectEntry, attr), attr
