"""URL grammar: parsing, option assignment, errors, the scheme registry, opening."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from omnibot.errors import ConfigError, LinkError
from omnibot.transport import (
    FaultLink,
    LinkUrl,
    LockstepLink,
    SerialLink,
    SpyLink,
    open_link,
    parse_link_url,
    register_scheme,
    registered_schemes,
    unregister_scheme,
)
from omnibot.transport import url as url_module

from .fakes import EchoDevice


@pytest.fixture
def fake_sim() -> Iterator[list[LinkUrl]]:
    """Register a fake ``sim`` scheme (an echo device) for the test; restore afterwards."""
    seen: list[LinkUrl] = []
    before = registered_schemes().get("sim")

    def factory(u: LinkUrl) -> LockstepLink:
        seen.append(u)
        device = EchoDevice(latency=u.get_int("seed", 2) / 1000)
        return LockstepLink(device, baud=u.get_int("baud", 115200, minimum=0), url=u.url)

    register_scheme("sim", factory, options=("seed", "surface", "world", "baud"))
    yield seen
    unregister_scheme("sim")
    if before is not None:
        register_scheme("sim", before.factory, options=before.options, help=before.help)


def test_bare_path_is_serial() -> None:
    (layer,) = parse_link_url("/dev/ttyUSB0")
    assert (layer.scheme, layer.target, dict(layer.options)) == ("serial", "/dev/ttyUSB0", {})
    assert layer.url == "/dev/ttyUSB0"
    assert layer.text == "serial:///dev/ttyUSB0"


def test_serial_url_with_options() -> None:
    (layer,) = parse_link_url("serial:///dev/ttyUSB0?baud=57600&retry=2.5")
    assert layer.target == "/dev/ttyUSB0"
    assert layer.get_int("baud", 115200) == 57600
    assert layer.get_float("retry", 0.0) == 2.5


@pytest.mark.usefixtures("fake_sim")
def test_wrappers_and_option_assignment() -> None:
    spy, faults, sim = parse_link_url("spy+faults+sim://omni4?seed=3&drop=0.1&faults.seed=7&all")
    assert (spy.scheme, faults.scheme, sim.scheme, sim.target) == ("spy", "faults", "sim", "omni4")
    assert dict(sim.options) == {"seed": "3"}  # innermost layer with that option wins
    assert dict(faults.options) == {"drop": "0.1", "seed": "7"}
    assert dict(spy.options) == {"all": ""}
    assert spy.get_bool("all") is True
    assert spy.url == "spy+faults+sim://omni4?seed=3&drop=0.1&faults.seed=7&all"
    assert faults.url == ""
    assert sim.url == "sim://omni4?seed=3"


def test_tcp_options_go_to_faults_when_tcp_has_none() -> None:
    faults, tcp = parse_link_url("faults+tcp://localhost:4000?seed=1&connect_timeout=2")
    assert dict(faults.options) == {"seed": "1"}
    assert dict(tcp.options) == {"connect_timeout": "2"}


@pytest.mark.parametrize(
    ("url", "words"),
    [
        ("", ["non-empty"]),
        ("serial://", ["no serial device path"]),
        ("ftp://host", ["unknown link scheme 'ftp'", "valid schemes:", "tcp", "serial", "sim", "spy+"]),
        ("tpc://host:1", ["did you mean 'tcp'"]),
        ("spi+tcp://h:1", ["unknown wrapper 'spi'", "did you mean 'spy'", "faults+"]),
        ("/dev/ttyUSB0?bud=9600", ["unknown option", "did you mean 'baud'", "serial: baud, retry"]),
        ("/dev/ttyUSB0?baud=fast", ["baud", "expected an integer", "'fast'"]),
        ("/dev/ttyUSB0?baud=0", ["baud", ">= 1"]),
        ("/dev/ttyUSB0?baud=1&baud=2", ["baud", "twice"]),
        ("faults+tcp://h:1?drop=2", ["drop", "in [0.0, 1.0]"]),
        ("faults+tcp://h:1?dir=up", ["dir", "both, tx or rx"]),
        ("faults+tcp://h:1?spy.file=x", ["layer 'spy'", "layers: faults, tcp"]),
        ("faults+tcp://h:1?faults.baud=1", ["unknown option", "faults: drop"]),
        ("tcp://localhost", ["expected tcp://host:port"]),
        ("tcp://localhost:99999", ["host:port"]),
        ("tcp://:4000", ["expected tcp://host:port"]),
    ],
)
def test_bad_urls_say_what_is_wrong(url: str, words: list[str]) -> None:
    with pytest.raises(ConfigError) as info:
        open_link(url)
    message = str(info.value)
    for word in words:
        assert word in message
    assert isinstance(info.value, ValueError)


def test_missing_device_is_a_link_error() -> None:
    with pytest.raises(LinkError, match="/dev/does-not-exist"):
        open_link("/dev/does-not-exist")


def test_sim_scheme_via_registry(fake_sim: list[LinkUrl]) -> None:
    with open_link("sim://omni4?seed=5&surface=carpet&baud=0") as link:
        assert isinstance(link, LockstepLink)
        assert link.url == "sim://omni4?seed=5&surface=carpet&baud=0"
        link.write(b"hi\n")
        assert link.read(timeout=1) == b"hi\n"
    (u,) = fake_sim
    assert (u.target, u.get_str("surface", ""), u.get_str("world", "flat")) == ("omni4", "carpet", "flat")


def test_sim_scheme_is_imported_from_its_provider(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(url_module.SCHEME_PROVIDERS, "fakesim", "omnibot.no_such_module_xyz")
    with pytest.raises(LinkError, match=r"fakesim:// links are not available.*no_such_module_xyz"):
        open_link("fakesim://x")


def test_provider_that_does_not_register(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(url_module.SCHEME_PROVIDERS, "fakesim", "omnibot.errors")
    with pytest.raises(LinkError, match="did not register"):
        open_link("fakesim://x")


@pytest.mark.usefixtures("fake_sim")
def test_wrapped_open(tmp_path: Path) -> None:
    trace = tmp_path / "trace.txt"
    url = f"spy+faults+sim://omni4?file={trace}&faults.seed=1"
    with open_link(url) as link:
        assert isinstance(link, SpyLink)
        assert isinstance(link.inner, FaultLink)
        assert isinstance(link.inner.inner, LockstepLink)
        assert link.url == url
        assert link.inner.url == "faults+sim://omni4"
        assert link.clock.now() == 0.0
        link.write(b"ping\n")
        assert link.read(timeout=1) == b"ping\n"
        assert link.clock.now() > 0.0
    text = trace.read_text()
    assert "TX" in text and "RX" in text and "ping." in text


@pytest.mark.usefixtures("fake_sim")
def test_wrapper_failure_closes_inner() -> None:
    opened: list[LockstepLink] = []

    def factory(u: LinkUrl) -> LockstepLink:
        link = LockstepLink(EchoDevice())
        opened.append(link)
        return link

    register_scheme("sim", factory, options=("seed",))
    with pytest.raises(ConfigError, match="trace file"):
        open_link("spy+sim://x?file=/nonexistent-dir/trace.txt")
    assert opened and opened[0].closed


def test_loop_passthrough() -> None:
    with open_link("loop://?baud=9600") as link:
        assert isinstance(link, SerialLink)
        assert link.baud == 9600
        link.write(b"abc")
        assert link.read(timeout=1) == b"abc"


def test_register_scheme_rejects_bad_names() -> None:
    with pytest.raises(ValueError):
        register_scheme("spy", lambda u: open_link("loop://"))
    with pytest.raises(ValueError):
        register_scheme("no spaces", lambda u: open_link("loop://"))


def test_stderr_spy_does_not_close_stderr() -> None:
    with open_link("spy+loop://") as link:
        link.write(b"x")
    assert not sys.stderr.closed
