"""Benchmark results: every run, a summary per configuration and the OMPL logs per problem."""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Optional, Union

import numpy as np

from ._stubs import pb
from .convert import outcome_name


@dataclass
class BenchmarkProgress:
    """Progress sent with every message of the Benchmark stream.

    Attributes:
        done: runs finished; total: problems × configurations × runs; running: runs executing now;
        elapsed: seconds since the benchmark started [s]; eta: estimated seconds left [s], -1 = unknown.
    """

    done: int
    total: int
    running: int
    elapsed: float
    eta: float

    @classmethod
    def from_message(cls, message: pb.BenchmarkProgress) -> "BenchmarkProgress":
        return cls(done=message.done, total=message.total, running=message.running,
                   elapsed=message.elapsed, eta=message.eta)


@dataclass
class BenchmarkRun:
    """One finished run (chasles.v1.BenchmarkRun) with its problem's and configuration's names.

    Times in seconds, lengths in radians, clearance in metres (-1 when unsolved), memory in bytes.
    """

    problem: int
    config: int
    run: int
    seed: int
    outcome: str
    message: str
    solved: bool
    approximate: bool
    plan_time: float
    post_time: float
    total_time: float
    path_length: float
    raw_path_length: float
    duration: float
    smoothness: float
    jerk_integral: float
    min_clearance: float
    collision_checks: int
    graph_states: int
    peak_memory: int
    worker: int
    problem_name: str = ""
    config_name: str = ""

    @classmethod
    def from_message(cls, message: pb.BenchmarkRun, problem_name: str = "", config_name: str = "") -> "BenchmarkRun":
        values: Dict[str, Any] = {}
        for f in dataclasses.fields(cls):
            if f.name in ("problem_name", "config_name"):
                continue
            value = getattr(message, f.name)
            values[f.name] = outcome_name(value) if f.name == "outcome" else value
        return cls(problem_name=problem_name, config_name=config_name, **values)


#: Columns of ``BenchmarkResult.to_array()`` (every BenchmarkRun field but the message).
RUN_DTYPE = np.dtype([
    ("problem", np.int32), ("config", np.int32), ("problem_name", "U64"), ("config_name", "U64"),
    ("run", np.int32), ("seed", np.uint64), ("outcome", "U32"), ("solved", np.bool_), ("approximate", np.bool_),
    ("plan_time", np.float64), ("post_time", np.float64), ("total_time", np.float64),
    ("path_length", np.float64), ("raw_path_length", np.float64), ("duration", np.float64),
    ("smoothness", np.float64), ("jerk_integral", np.float64), ("min_clearance", np.float64),
    ("collision_checks", np.uint64), ("graph_states", np.uint64), ("peak_memory", np.uint64),
    ("worker", np.int32),
])


@dataclass
class ConfigSummary:
    """Summary of one configuration over all problems (chasles.v1.ConfigSummary).

    Medians of times [s], path length [rad], duration [s], clearance [m] and peak memory [bytes];
    lengths, durations and clearances over solved runs only (0 when none solved).
    """

    config: int
    name: str
    runs: int
    solved: int
    approximate: int
    success_rate: float
    median_time: float
    p95_time: float
    median_plan_time: float
    median_length: float
    median_duration: float
    median_clearance: float
    median_peak_memory: float

    @classmethod
    def from_message(cls, message: pb.ConfigSummary) -> "ConfigSummary":
        return cls(**{f.name: getattr(message, f.name) for f in dataclasses.fields(cls)})


def _quantile(values: List[float], p: float) -> float:
    """The server's quantile (linear between the two nearest of the sorted values); 0 when empty."""
    if not values:
        return 0.0
    ordered = sorted(values)
    position = min(max(p, 0.0), 1.0) * (len(ordered) - 1)
    below = int(position)
    above = min(below + 1, len(ordered) - 1)
    return ordered[below] + (position - below) * (ordered[above] - ordered[below])


def summarize_configs(runs: List["BenchmarkRun"], config_names: List[str]) -> List[ConfigSummary]:
    """ConfigSummary per configuration from runs, as the server computes it (for merged results)."""
    out = []
    for c, name in enumerate(config_names):
        mine = [r for r in runs if r.config == c]
        solved = [r for r in mine if r.solved]
        out.append(ConfigSummary(
            config=c, name=name, runs=len(mine), solved=len(solved),
            approximate=sum(1 for r in mine if r.approximate),
            success_rate=len(solved) / len(mine) if mine else 0.0,
            median_time=_quantile([r.total_time for r in mine], 0.5),
            p95_time=_quantile([r.total_time for r in mine], 0.95),
            median_plan_time=_quantile([r.plan_time for r in mine], 0.5),
            median_length=_quantile([r.path_length for r in solved], 0.5),
            median_duration=_quantile([r.duration for r in solved], 0.5),
            median_clearance=_quantile([r.min_clearance for r in solved], 0.5),
            median_peak_memory=_quantile([float(r.peak_memory) for r in mine], 0.5)))
    return out


_RUNS_LINE = re.compile(r"^(\d+) runs$")


def merge_ompl_logs(logs: List[str], runs_per_planner: int, seconds: float) -> str:
    """One problem's OMPL benchmark logs from several shards as one: the first's header and
    settings, every shard's run rows under each planner (in shard order), totals updated."""
    lines = [text.split("\n") for text in logs]
    run_lines = [[i for i, line in enumerate(shard) if _RUNS_LINE.match(line)] for shard in lines]
    if any(len(r) != len(run_lines[0]) for r in run_lines):
        raise ValueError("the shards' OMPL logs list different planners")
    out: List[str] = []

    def copy(start: int, until: int) -> None:
        for line in lines[0][start:until]:
            if line.endswith(" runs per planner"):
                out.append(f"{runs_per_planner} runs per planner")
            elif line.endswith(" seconds spent to collect the data"):
                out.append(f"{seconds:.6g} seconds spent to collect the data")
            else:
                out.append(line)

    start = 0
    for p, at0 in enumerate(run_lines[0]):
        copy(start, at0)
        rows: List[str] = []
        for shard, at in zip(lines, (r[p] for r in run_lines)):
            n = int(_RUNS_LINE.match(shard[at]).group(1))
            rows += shard[at + 1:at + 1 + n]
        out.append(f"{len(rows)} runs")
        out += rows
        start = at0 + 1 + int(_RUNS_LINE.match(lines[0][at0]).group(1))
    copy(start, len(lines[0]))
    return "\n".join(out)


def _file_name(name: str) -> str:
    """A file-system-safe version of a problem name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "problem"


@dataclass
class BenchmarkResult:
    """The whole answer of a Benchmark call.

    Attributes:
        runs: every finished run, in the order they finished.
        summaries: one ConfigSummary per configuration, in request order.
        ompl_logs: problem name -> the OMPL benchmark log text of that problem
            (``ompl_benchmark_statistics FILE.log -d results.db`` reads it).
        stopped: StopBenchmark ended it early (runs in flight were dropped).
        runs_finished, runs_total, wall_time [s], parallelism, request_id: from the summary.
    """

    request_id: str
    problem_names: List[str]
    config_names: List[str]
    runs: List[BenchmarkRun] = field(default_factory=list)
    summaries: List[ConfigSummary] = field(default_factory=list)
    ompl_logs: Dict[str, str] = field(default_factory=dict)
    runs_finished: int = 0
    runs_total: int = 0
    stopped: bool = False
    wall_time: float = 0.0
    parallelism: int = 0

    # -- building from the stream ---------------------------------------------------------------

    @classmethod
    def from_stream(cls, responses: Iterable[pb.BenchmarkResponse], request: pb.BenchmarkRequest,
                    on_progress: Optional[Callable[[BenchmarkProgress], Any]] = None,
                    on_run: Optional[Callable[[BenchmarkRun], Any]] = None) -> "BenchmarkResult":
        """Consumes a Benchmark response stream; calls ``on_progress`` for every message and
        ``on_run`` for every finished run (from the calling thread, as they arrive).

        Names before the summary arrives are the request's (or the server's defaults:
        ``problem<index>``, the planner id).
        """
        problem_names = [p.name or f"problem{i}" for i, p in enumerate(request.problems)]
        config_names = _default_config_names(request)
        result = cls(request_id=request.request_id, problem_names=problem_names, config_names=config_names)
        summary: Optional[pb.BenchmarkSummary] = None
        for response in responses:
            if response.HasField("run"):
                run = response.run
                run_result = BenchmarkRun.from_message(
                    run, _name(result.problem_names, run.problem), _name(result.config_names, run.config))
                result.runs.append(run_result)
                if on_run is not None:
                    on_run(run_result)
            if response.HasField("progress") and on_progress is not None:
                on_progress(BenchmarkProgress.from_message(response.progress))
            if response.HasField("summary"):
                summary = response.summary
        if summary is not None:
            result._apply_summary(summary)
        else:
            result.runs_finished = len(result.runs)
        return result

    @classmethod
    def merge(cls, parts: List["BenchmarkResult"], first_runs: List[int], request_id: str,
              wall_time: float) -> "BenchmarkResult":
        """The results of shards of one benchmark (shard k ran runs first_runs[k] … of the whole,
        seeded as they would be there) as one: runs renumbered, summaries recomputed from all
        runs, each problem's OMPL log merged."""
        head = parts[0]
        merged = cls(request_id=request_id, problem_names=list(head.problem_names), config_names=list(head.config_names))
        for part, first in zip(parts, first_runs):
            merged.runs += [dataclasses.replace(run, run=run.run + first) for run in part.runs]
        merged.summaries = summarize_configs(merged.runs, merged.config_names)
        merged.runs_total = sum(p.runs_total for p in parts)
        merged.runs_finished = len(merged.runs)
        merged.stopped = any(p.stopped for p in parts)
        merged.wall_time = wall_time
        merged.parallelism = sum(p.parallelism for p in parts)
        cells = max(1, len(merged.problem_names) * len(merged.config_names))
        for name in head.ompl_logs:
            texts = [p.ompl_logs[name] for p in parts if name in p.ompl_logs]
            merged.ompl_logs[name] = merge_ompl_logs(texts, merged.runs_total // cells, wall_time)
        return merged

    def _apply_summary(self, summary: pb.BenchmarkSummary) -> None:
        if summary.problem_names:
            self.problem_names = list(summary.problem_names)
        if summary.config_names:
            self.config_names = list(summary.config_names)
        for run in self.runs:
            run.problem_name = _name(self.problem_names, run.problem)
            run.config_name = _name(self.config_names, run.config)
        self.summaries = [ConfigSummary.from_message(c) for c in summary.configs]
        self.ompl_logs = {(log.name or _name(self.problem_names, log.problem)): log.ompl_log for log in summary.logs}
        self.runs_finished = summary.runs_finished
        self.runs_total = summary.runs_total
        self.stopped = summary.stopped
        self.wall_time = summary.wall_time
        self.parallelism = summary.parallelism
        if summary.request_id:
            self.request_id = summary.request_id

    # -- views ----------------------------------------------------------------------------------

    @property
    def summary(self) -> Dict[str, ConfigSummary]:
        """Configuration name -> its summary."""
        return {s.name: s for s in self.summaries}

    def to_array(self) -> np.ndarray:
        """The runs as a numpy structured array with ``RUN_DTYPE`` (one row per run)."""
        rows = [tuple(getattr(run, name) for name in RUN_DTYPE.names) for run in self.runs]
        return np.array(rows, dtype=RUN_DTYPE)

    def columns(self) -> Dict[str, np.ndarray]:
        """The runs as a dict of 1-D arrays, one per ``RUN_DTYPE`` column."""
        array = self.to_array()
        return {name: array[name] for name in RUN_DTYPE.names}

    def times_by_config(self, column: str = "total_time") -> Dict[str, np.ndarray]:
        """Configuration name -> the ``column`` values of its runs (all problems), request order."""
        array = self.to_array()
        return {name: array[column][array["config"] == i] for i, name in enumerate(self.config_names)}

    def success_rates(self) -> Dict[str, float]:
        """Configuration name -> solved / finished runs (from the summary, else from the runs)."""
        if self.summaries:
            return {s.name: s.success_rate for s in self.summaries}
        array = self.to_array()
        rates: Dict[str, float] = {}
        for i, name in enumerate(self.config_names):
            mine = array["solved"][array["config"] == i]
            rates[name] = float(mine.mean()) if len(mine) else 0.0
        return rates

    # -- files ----------------------------------------------------------------------------------

    def write_ompl_logs(self, directory: Union[str, os.PathLike]) -> List[Path]:
        """Writes each problem's OMPL benchmark log to ``directory/<problem>.log``; returns the paths."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        paths = []
        for name, text in self.ompl_logs.items():
            path = directory / f"{_file_name(name)}.log"
            path.write_text(text)
            paths.append(path)
        return paths

    def write_csv(self, path: Union[str, os.PathLike]) -> Path:
        """Writes one row per run (every BenchmarkRun field, header first)."""
        path = Path(path)
        names = [f.name for f in dataclasses.fields(BenchmarkRun)]
        with path.open("w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=names)
            writer.writeheader()
            for run in self.runs:
                writer.writerow(dataclasses.asdict(run))
        return path

    def to_dict(self) -> Dict[str, Any]:
        """Everything as plain JSON-ready data."""
        return dataclasses.asdict(self)

    def write_json(self, path: Union[str, os.PathLike]) -> Path:
        """Writes ``to_dict()`` as JSON."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=1))
        return path


def _name(names: List[str], index: int) -> str:
    return names[index] if 0 <= index < len(names) else str(index)


def _default_config_names(request: pb.BenchmarkRequest) -> List[str]:
    """The server's default names: the name, else the planner id, plus "#<index>" when repeated."""
    ids = [c.planner.planner_id or "rrt_connect" for c in request.configs]
    return [c.name or (ids[i] + (f"#{i}" if ids.count(ids[i]) > 1 else ""))
            for i, c in enumerate(request.configs)]
