"""Plots of a commissioning run as inline SVG (matplotlib, Agg/SVG backends, no pyplot state).

Text stays text (``svg.fonttype: none``) so that a page can be searched and tested for its labels; the ids
inside each figure get a prefix of their own, so several figures can sit inline in one page.
"""

from __future__ import annotations

import io
import re
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ecattool.commission.trace import DriveTrace

#: colours of the states on the timeline (others grey)
STATE_COLOURS = {
    "INIT": "#d9d9d9", "PREOP": "#c6dbef", "SAFEOP": "#fdd0a2", "OP": "#a1d99b", "BOOT": "#e0c0e0",
    "switch on disabled": "#d9d9d9", "not ready to switch on": "#eeeeee", "ready to switch on": "#c6dbef",
    "switched on": "#9ecae1", "operation enabled": "#a1d99b", "quick stop active": "#fdd0a2",
    "fault reaction active": "#fc9272", "fault": "#ef3b2c",
}
#: matplotlib settings of every figure (typed Any: matplotlib types rc keys as a Literal of its own names)
_RC: Any = {"svg.fonttype": "none", "font.size": 9, "font.family": "DejaVu Sans", "axes.grid": True,
       "grid.alpha": 0.35, "axes.spines.top": False, "axes.spines.right": False}


def _svg(fig: Any, uid: str) -> str:
    import matplotlib

    buf = io.StringIO()
    rc: Any = {**_RC, "svg.hashsalt": uid}  # stable ids inside the figure, distinct between figures
    with matplotlib.rc_context(rc):
        fig.savefig(buf, format="svg", metadata={"Date": None, "Creator": "ecattool"})
    text = buf.getvalue()
    text = text[text.index("<svg"):]  # inline: no XML declaration, no DOCTYPE
    # ids unique in the page: every id, url(#…) and href="#…" of this figure gets the figure's prefix
    text = re.sub(r'\bid="([^"]+)"', rf'id="{uid}-\1"', text)
    text = re.sub(r"url\(#([^)]+)\)", rf"url(#{uid}-\1)", text)
    return re.sub(r'href="#([^"]+)"', rf'href="#{uid}-\1"', text)


def _figure(width: float, height: float, right: float = 0.88, bottom: float = 0.16) -> Any:
    import matplotlib
    from matplotlib.figure import Figure

    with matplotlib.rc_context(_RC):
        fig = Figure(figsize=(width, height), dpi=96)
    # fixed margins (a layout engine doubles the drawing time): room for tick labels, a second y axis, a legend
    fig.subplots_adjust(left=0.1, right=right, bottom=bottom, top=0.88)
    return fig


def timeline_svg(trace: DriveTrace, uid: str) -> str | None:
    """EtherCAT states and CiA-402 states over process-data cycles, as two lanes of coloured bars."""
    import matplotlib

    if not trace.events:
        return None
    end = max(trace.cycles, max(e.cycle for e in trace.events)) + 1
    with matplotlib.rc_context(_RC):
        fig = _figure(9.0, 2.4, right=0.78, bottom=0.22)
        ax = fig.add_subplot()
        seen: dict[str, str] = {}
        for lane, layer in ((1, "ethercat"), (0, "cia402")):
            events = [e for e in trace.events if e.layer == layer]
            for i, e in enumerate(events):
                stop = events[i + 1].cycle if i + 1 < len(events) else end
                width = max(stop - e.cycle, 0.6)
                colour = seen.setdefault(e.state, STATE_COLOURS.get(e.state, "#cccccc"))
                ax.broken_barh([(e.cycle, width)], (lane - 0.38, 0.76), facecolors=colour, edgecolors="#444444",
                               linewidth=0.6)
                if width / end * 620 > len(e.state) * 5.2:  # the name fits in its bar (axes ≈ 620 px wide)
                    ax.text(e.cycle + width / 2, lane, e.state, va="center", ha="center", fontsize=7.5)
        from matplotlib.patches import Patch

        handles = [Patch(facecolor=c, edgecolor="#444444", label=s) for s, c in seen.items()]
        if trace.move_cycles is not None:
            a, b = trace.move_cycles
            handles.append(ax.axvspan(a, b, color="#ffe9a8", alpha=0.5, zorder=0, label="commissioning move"))
        ax.legend(handles=handles, loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=7.5, frameon=False)
        ax.set_yticks([0, 1], ["CiA-402", "EtherCAT"])
        ax.set_ylim(-0.6, 1.9)
        ax.set_xlim(0, end)
        ax.set_xlabel("process-data cycle")
        ax.set_title("State timeline", loc="left", fontsize=10, fontweight="bold")
        ax.grid(axis="y", visible=False)
    return _svg(fig, uid)


#: a velocity from integer positions is fitted over a window spanning at least this many position steps
#: (quanta), so that 1 unit every 11 cycles reads as a steady velocity, not as spikes of one unit per cycle
QUANTA_PER_WINDOW = 10


def derivative(cycles: list[int], values: list[int], cycle_s: float) -> tuple[list[float], int]:
    """Velocity from sampled integer positions, per second: the least-squares slope over a centred window of
    samples wide enough to span :data:`QUANTA_PER_WINDOW` position steps on average (at most a quarter of the
    samples; narrower at the ends). Returns the velocities and the window in samples."""
    n = len(values)
    travel = abs(values[-1] - values[0]) if n else 0
    window = min(max(1, -(-QUANTA_PER_WINDOW * n // travel) if travel else 1), max(1, n // 4))
    half = max(1, window // 2)
    ts = [c * cycle_s for c in cycles]
    # prefix sums of t, x, t·t, t·x: each window's slope in constant time
    st, sx, stt, stx = [0.0], [0.0], [0.0], [0.0]
    for t, x in zip(ts, values):
        st.append(st[-1] + t)
        sx.append(sx[-1] + x)
        stt.append(stt[-1] + t * t)
        stx.append(stx[-1] + t * x)
    out = []
    for i in range(n):
        a, b = max(i - half, 0), min(i + half, n - 1) + 1
        k = b - a
        t_sum, x_sum = st[b] - st[a], sx[b] - sx[a]
        var = (stt[b] - stt[a]) - t_sum * t_sum / k
        out.append(((stx[b] - stx[a]) - t_sum * x_sum / k) / var if k > 1 and var > 0 else 0.0)
    return out, window


def _from_zero(ax: Any) -> None:
    """Let a velocity axis include 0 (a steady velocity then reads as a flat line, not as its own noise)."""
    lo, hi = ax.get_ylim()
    lo, hi = min(lo, 0.0), max(hi, 0.0)
    ax.set_ylim(lo - 0.04 * (hi - lo) * (lo < 0), hi + 0.06 * (hi - lo))


def _window_note(window: int, ms: float, cycles: list[int]) -> str:
    span = (cycles[min(window, len(cycles) - 1)] - cycles[0]) * ms if window > 1 else 0
    return f", over {span:g} ms" if span else ""


def move_svgs(trace: DriveTrace, uid: str) -> list[tuple[str, str]]:
    """(title, SVG) of the move: position in user units, velocity in user units, both in internal units."""
    import matplotlib

    if len(trace.samples) < 2:
        return []
    channels = {c.key: c for c in trace.channels}
    t0 = trace.samples[0].cycle
    ms = trace.cycle_s * 1000

    def series(key: str) -> tuple[list[float], list[int], list[int]]:
        pts = [(s.cycle, s.values[key]) for s in trace.samples if key in s.values]
        return [(c - t0) * ms for c, _ in pts], [c for c, _ in pts], [v for _, v in pts]

    pu = trace.units.get("position", "user units")
    vu = trace.units.get("velocity", f"{pu}/s")
    xlabel = f"time [ms] (process-data cycles of {ms:g} ms)"
    figures: list[tuple[str, str]] = []
    with matplotlib.rc_context(_RC):
        # position, user units
        fig = _figure(9.0, 3.0)
        ax = fig.add_subplot()
        for key, style in (("target", dict(ls="--", color="#888888")), ("demand", dict(color="#1f77b4")),
                           ("actual", dict(color="#d62728", ls=":", lw=2))):
            if key in channels:
                x, _, y = series(key)
                ax.plot(x, y, label=channels[key].label, **style)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"position [{pu}]")
        ax.set_title(f"Position (user units, {pu})", loc="left", fontsize=10, fontweight="bold")
        ax.legend(fontsize=7.5, frameon=False)
        figures.append((f"Position (user units, {pu})", _svg(fig, f"{uid}-pos")))
        # velocity, user units: the demand's difference quotient (position unit/s) and the drive's 606Ch
        # (velocity unit; on an axis of its own where the two units differ, e.g. um/s and mm/s)
        fig = _figure(9.0, 3.0)
        ax = fig.add_subplot()
        own = vu != f"{pu}/s"
        lines = []
        if "demand" in channels:
            x, c, y = series("demand")
            v, window = derivative(c, y, trace.cycle_s)
            lines += ax.plot(x, v, color="#1f77b4",
                             label=f"demand velocity (from 6062h{_window_note(window, ms, c)}) [{pu}/s]")
        ax.set_ylabel(f"velocity [{pu}/s]")
        if "velocity" in channels:
            vax = ax.twinx() if own and "demand" in channels else ax
            x, _, y = series("velocity")
            lines += vax.plot(x, y, color="#d62728", ls=":", lw=2, label=f"{channels['velocity'].label} [{vu}]")
            vax.set_ylabel(f"velocity [{vu}]")
            vax.grid(vax is ax)
        for a in {ax, *(ln.axes for ln in lines)}:
            _from_zero(a)
        ax.set_xlabel(xlabel)
        ax.set_title(f"Velocity (user units, {vu})", loc="left", fontsize=10, fontweight="bold")
        ax.legend(lines, [str(ln.get_label()) for ln in lines], fontsize=7.5, frameon=False)
        figures.append((f"Velocity (user units, {vu})", _svg(fig, f"{uid}-vel")))
        # internal units: 6063h and its difference quotient
        if "internal" in channels:
            fig = _figure(9.0, 3.0)
            ax = fig.add_subplot()
            x, c, y = series("internal")
            ax.plot(x, y, color="#2ca02c", label="6063h position actual [counts]")
            ax.set_ylabel("position [counts]")
            ax2 = ax.twinx()
            v, window = derivative(c, y, trace.cycle_s)
            ax2.plot(x, v, color="#9467bd", ls="--",
                     label=f"velocity (from 6063h{_window_note(window, ms, c)}) [counts/s]")
            ax2.set_ylabel("velocity [counts/s]")
            _from_zero(ax2)
            ax2.grid(False)
            ax.set_xlabel(xlabel)
            ax.set_title("Internal units (counts)", loc="left", fontsize=10, fontweight="bold")
            lines = ax.get_lines() + ax2.get_lines()
            ax.legend(lines, [str(ln.get_label()) for ln in lines], fontsize=7.5, frameon=False, loc="upper left")
            figures.append(("Internal units (counts)", _svg(fig, f"{uid}-int")))
        # following error (60F4h, else demand - actual) with the window 6065h, and the torque 6077h
        if "actual" in channels and ("error" in channels or "demand" in channels):
            fig = _figure(9.0, 3.0)
            ax = fig.add_subplot()
            if "error" in channels:
                x, _, y = series("error")
                label = f"{channels['error'].label} [{pu}]"
            else:
                pts = [(s.cycle, s.values["demand"] - s.values["actual"]) for s in trace.samples
                       if "demand" in s.values and "actual" in s.values]
                x, y = [(c - t0) * ms for c, _ in pts], [v for _, v in pts]
                label = f"6062h - 6064h following error [{pu}]"
            lines = ax.plot(x, y, color="#d62728", label=label)
            if trace.error_window is not None:
                for sign in (1, -1):
                    ax.axhline(sign * trace.error_window, color="#888888", ls="--", lw=1)
                lines += ax.plot([], [], color="#888888", ls="--", lw=1,
                                 label=f"6065h following error window ±{trace.error_window}")
            ax.set_ylabel(f"following error [{pu}]")
            if "torque" in channels:
                tax = ax.twinx()
                x, _, y = series("torque")
                lines += tax.plot(x, [v / 10 for v in y], color="#9467bd", ls=":", lw=2,
                                  label="6077h torque actual [% of rated]")
                tax.set_ylabel("torque [% of rated]")
                tax.grid(False)
            ax.set_xlabel(xlabel)
            ax.set_title("Following error and torque", loc="left", fontsize=10, fontweight="bold")
            ax.legend(lines, [str(ln.get_label()) for ln in lines], fontsize=7.5, frameon=False, loc="upper left")
            figures.append(("Following error and torque", _svg(fig, f"{uid}-fe")))
    return figures
