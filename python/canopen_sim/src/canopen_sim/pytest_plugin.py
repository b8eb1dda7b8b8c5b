"""pytest plugin (entry point pytest11): a running simulated drive in one line.

    def test_trip(canopen_sim):              # canopen-drive with a VF-S15, node 5, on vcan0
        canopen_sim.fault(5, 0x01)

    @pytest.mark.canopen_sim(drives=[("benshaw-rsi", 7)], iface="vcan0", trace="bus.log")
    def test_other(canopen_sim): ...

The simulator is $CANOPEN_DRIVE_BIN (else canopen-drive on PATH); the interface $CANOPEN_IFACE
(else vcan0) unless the marker says; it is stopped after the test and must exit 0.
`canopen_sim_factory(...)` starts more (same arguments as Simulator)."""
import os

import pytest

from .simulator import Simulator


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "canopen_sim(drives=[(drive_id, node_id)], iface=..., **options): what the "
                   "canopen_sim fixture starts (options as canopen_sim.Simulator)")


def _timeout():
    return float(os.environ.get("CANOPEN_TIMEOUT", "5"))


@pytest.fixture
def canopen_sim_factory():
    """Starts simulators: factory(drives=[...], iface=..., **options) -> a running Simulator.
    All are stopped after the test; each must exit 0."""
    started = []

    def start(drives=(("vf-s15", 5),), iface=None, **options):
        options.setdefault("timeout", _timeout())
        options.setdefault("wrapper", os.environ.get("CANOPEN_DRIVE_WRAPPER") or None)
        sim = Simulator(drives, iface=iface or os.environ.get("CANOPEN_IFACE", "vcan0"),
                        **options)
        started.append(sim)
        return sim.start()

    yield start
    errors = []
    for sim in started:
        try:
            sim.stop()
        except Exception as e:  # report every one, not only the first
            errors.append(str(e))
    assert not errors, "; ".join(errors)


@pytest.fixture
def canopen_sim(request, canopen_sim_factory):
    """A running canopen-drive (default: a VF-S15 as node 5 on vcan0); see the module doc."""
    marker = request.node.get_closest_marker("canopen_sim")
    options = dict(marker.kwargs) if marker else {}
    return canopen_sim_factory(**options)
