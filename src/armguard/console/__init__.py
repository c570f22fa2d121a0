"""The operator console in the browser: Ranger's GUI and WORKMATE's emulation time line.

:class:`ConsoleState` is the whole console without a browser (state, commands, status);
:class:`ConsoleApp` binds it to viser widgets and a 3-D view; :func:`serve` does both.
"""

from ._app import ConsoleApp
from ._parse import ConsoleInputError, parse_number, parse_numbers
from ._plot import ClearancePlot
from ._readout import PANEL_COLORS, CategoryRow, PanelStatus, Readout, panel_html, readout_from_report, readout_off
from ._serve import serve
from ._state import ConsoleState, Player, Snapshot
from ._tasks import TaskComposer
from ._timeline import Timeline, TimelineState
from ._views import VIEWS, VISTA_POINTS, view_pose

__all__ = [
    "ConsoleState",
    "ConsoleApp",
    "serve",
    "Snapshot",
    "Player",
    "Timeline",
    "TimelineState",
    "Readout",
    "CategoryRow",
    "PanelStatus",
    "PANEL_COLORS",
    "readout_from_report",
    "readout_off",
    "panel_html",
    "ClearancePlot",
    "ConsoleInputError",
    "parse_number",
    "parse_numbers",
    "VIEWS",
    "VISTA_POINTS",
    "view_pose",
    "TaskComposer",
]
