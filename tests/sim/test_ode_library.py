"""Loading SimSpark's engine: the library must be ODE 0.16 (or its ABI successors) in double
precision; anything else is refused with what was found and how to fix it."""

from __future__ import annotations

from unittest import mock

import pytest

from robocup_gym.sim.engines.ode import lib as ode_lib


def test_abi_version_from_file_names():
    assert ode_lib.abi_version("/usr/lib/x86_64-linux-gnu/libode.so.8.0.2") == 8
    assert ode_lib.abi_version("/opt/lib/libode.so.6") == 6
    assert ode_lib.abi_version("/usr/local/lib/libode.8.dylib") == 8
    assert ode_lib.abi_version("/somewhere/libode.so") is None


def _fake_library(configuration: bytes):
    fake = mock.MagicMock()
    fake.dGetConfiguration.return_value = configuration
    return fake


@pytest.fixture
def fresh_load():
    ode_lib.load.cache_clear()
    yield
    ode_lib.load.cache_clear()


def test_a_single_precision_build_is_refused(fresh_load):
    fake = _fake_library(b"ODE ODE_single_precision ODE_EXT_threading")
    with (
        mock.patch.object(ode_lib.ctypes, "CDLL", return_value=fake),
        pytest.raises(ode_lib.OdeUnavailableError) as err,
    ):
        ode_lib.load()
    text = str(err.value)
    assert "not a double-precision ODE build" in text and "ODE_single_precision" in text
    assert "libode8" in text and "engine='mujoco'" in text


def test_an_older_ode_is_refused(fresh_load):
    fake = _fake_library(b"ODE ODE_double_precision")
    with (
        mock.patch.object(ode_lib.ctypes, "CDLL", return_value=fake),
        mock.patch.object(ode_lib, "loaded_path", return_value="/opt/lib/libode.so.6.0.0"),
        pytest.raises(ode_lib.OdeUnavailableError) as err,
    ):
        ode_lib.load()
    text = str(err.value)
    assert "/opt/lib/libode.so.6.0.0 is ODE with library ABI 6" in text
    assert "apt-get install libode8" in text and "ROBOCUP_GYM_LIBODE" in text


def test_a_missing_library_names_the_install_command_and_the_other_engine(
    fresh_load, monkeypatch, tmp_path
):
    monkeypatch.setenv("ROBOCUP_GYM_LIBODE", str(tmp_path / "libode.so"))
    with pytest.raises(ode_lib.OdeUnavailableError) as err:
        ode_lib.load()
    text = str(err.value)
    assert "apt-get install libode8" in text and "brew install ode" in text
    assert "engine='mujoco'" in text


@pytest.mark.skipif(not ode_lib.available(), reason="no libode here (apt-get install libode8)")
def test_the_installed_library_is_accepted_and_is_double_precision():
    lib = ode_lib.load()
    assert "ODE_double_precision" in lib.dGetConfiguration().decode().split()
