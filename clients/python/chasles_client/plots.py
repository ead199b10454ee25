"""Figures of trajectories and benchmarks (matplotlib, Agg: no display needed).

Figures are built with ``matplotlib.figure.Figure`` directly, never through pyplot, so importing
this module changes no global matplotlib state. ``path`` saves the figure; the format follows
the file extension (.png, .svg or .pdf).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .benchmark import BenchmarkResult
from .trajectory import Trajectory

#: File extensions ``save_figure`` writes.
FORMATS = (".png", ".svg", ".pdf")

PathLike = Union[str, os.PathLike]


def save_figure(figure: Figure, path: PathLike, dpi: int = 120) -> Path:
    """Saves ``figure`` as PNG, SVG or PDF, by the extension of ``path``.

    Raises:
        ValueError: another extension.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"plot path {str(path)!r}: extension must be one of {list(FORMATS)}")
    figure.savefig(path, format=suffix[1:], dpi=dpi)
    return path


def _new_figure(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def plot_trajectory(trajectory: Any, velocity_limits: Optional[Sequence[float]] = None,
                    acceleration_limits: Optional[Sequence[float]] = None, path: Optional[PathLike] = None,
                    *, title: Optional[str] = None, joints: Optional[Sequence[int]] = None,
                    effort: bool = False) -> Figure:
    """Joint positions, velocities and accelerations against time, one colour per joint.

    Args:
        trajectory: a Trajectory, or a PlanResult / OptimizeResult (then its limits are used
            when ``velocity_limits`` / ``acceleration_limits`` are not given).
        velocity_limits, acceleration_limits: per joint [rad/s], [rad/s²]: drawn as dashed lines
            at ±limit in the joint's colour.
        path: where to save it (.png, .svg or .pdf); None = not saved.
        title: figure title; default the joint count and duration.
        joints: indices of the joints to draw; default all.
        effort: add a fourth panel with the joint torques (when the trajectory has them).

    Returns:
        the matplotlib Figure.
    """
    if not isinstance(trajectory, Trajectory):
        result = trajectory
        trajectory = getattr(result, "trajectory", None)
        if trajectory is None:
            raise ValueError(f"nothing to plot: the result has no trajectory "
                             f"(outcome {getattr(result, 'outcome', '?')}: {getattr(result, 'message', '')})")
        if velocity_limits is None:
            velocity_limits = getattr(result, "velocity_limits", None)
        if acceleration_limits is None:
            acceleration_limits = getattr(result, "acceleration_limits", None)
    indices = list(range(trajectory.dof)) if joints is None else list(joints)
    names = trajectory.joint_names or [f"joint{j + 1}" for j in range(trajectory.dof)]
    panels = [("position [rad]", trajectory.q, None),
              ("velocity [rad/s]", trajectory.qd, velocity_limits),
              ("acceleration [rad/s²]", trajectory.qdd, acceleration_limits)]
    if effort and trajectory.effort is not None:
        panels.append(("effort [N·m]", trajectory.effort, None))

    figure = _new_figure(10.0, 2.6 * len(panels) + 0.6)
    axes = figure.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    colours = [f"C{k % 10}" for k in range(len(indices))]
    for ax, (label, values, limits) in zip(axes, panels):
        for colour, j in zip(colours, indices):
            ax.plot(trajectory.t, values[:, j], color=colour, linewidth=1.3, label=names[j])
            if limits is not None:
                limit = float(np.asarray(limits, dtype=float)[j])
                ax.axhline(limit, color=colour, linestyle="--", linewidth=0.9, alpha=0.8)
                ax.axhline(-limit, color=colour, linestyle="--", linewidth=0.9, alpha=0.8)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
    if velocity_limits is not None or acceleration_limits is not None:
        axes[1].set_title("dashed: ± limits", fontsize="small", loc="right")
    figure.suptitle(title or f"{trajectory.dof}-joint trajectory, {trajectory.duration:.3f} s, "
                             f"{len(trajectory)} samples")
    if path is not None:
        save_figure(figure, path)
    return figure


def plot_benchmark(result: BenchmarkResult, path: Optional[PathLike] = None, *, column: str = "total_time",
                   title: Optional[str] = None) -> Figure:
    """Box plots of the run times per configuration (all problems) and a success-rate bar chart.

    Args:
        result: a BenchmarkResult.
        path: where to save it (.png, .svg or .pdf); None = not saved.
        column: the per-run value of the box plots, e.g. "total_time", "plan_time",
            "path_length" (a RUN_DTYPE column).
        title: figure title; default the problem and run counts.
    """
    names = list(result.config_names)
    values = result.times_by_config(column)
    rates = result.success_rates()
    figure = _new_figure(max(8.0, 1.6 * len(names) + 4.0), 4.4)
    time_ax, rate_ax = figure.subplots(1, 2, width_ratios=[3, 2])
    data = [values.get(name, np.zeros(0)) for name in names]
    positions = np.arange(1, len(names) + 1)
    filled = [k for k, d in enumerate(data) if len(d) > 0]
    if filled:
        time_ax.boxplot([data[k] for k in filled], positions=positions[filled], widths=0.6, showmeans=True)
    time_ax.set_xticks(positions, names, rotation=20, ha="right")
    time_ax.set_xlim(0.4, len(names) + 0.6)
    unit = "[s]" if column.endswith("time") or column == "duration" else ""
    time_ax.set_ylabel(f"{column.replace('_', ' ')} {unit}".strip())
    time_ax.set_title(f"{column.replace('_', ' ')} per run")
    time_ax.grid(True, axis="y", alpha=0.3)
    rate_values = [100.0 * rates.get(name, 0.0) for name in names]
    bars = rate_ax.bar(positions, rate_values, color=[f"C{k % 10}" for k in range(len(names))], width=0.6)
    rate_ax.bar_label(bars, labels=[f"{v:.0f}%" for v in rate_values], fontsize="small")
    rate_ax.set_xticks(positions, names, rotation=20, ha="right")
    rate_ax.set_ylim(0, 110)
    rate_ax.set_ylabel("solved [%]")
    rate_ax.set_title("success rate")
    rate_ax.grid(True, axis="y", alpha=0.3)
    runs = len(result.runs)
    figure.suptitle(title or f"{len(result.problem_names)} problem(s), {len(names)} configuration(s), {runs} runs"
                             + (" (stopped early)" if result.stopped else ""))
    if path is not None:
        save_figure(figure, path)
    return figure
