"""Drive the canopen-drive simulator from Python: start it (or attach to one running), inject
faults, read a drive's state, wait for its events.

Everything goes through the simulator's control socket (protocol version 1): a line-based text
protocol on a Unix socket (``--control PATH``) or on 127.0.0.1 (``--control-tcp PORT``).
"""
from .control import Control, ControlError, Event, PROTOCOL
from .lines import Lines, LineTimeout
from .simulator import Simulator, SimulatorError, find_binary

__all__ = ["Control", "ControlError", "Event", "Lines", "LineTimeout", "PROTOCOL", "Simulator",
           "SimulatorError", "find_binary"]
