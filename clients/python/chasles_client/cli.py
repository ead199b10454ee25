"""Command line: ``python3 -m chasles_client [--server ADDR] [--timeout S] COMMAND ...``.

Exit codes as the C++ ``chasles`` CLI: 0 ok, 1 failed (RPC error, or no trajectory / no run
solved), 2 bad arguments or unreadable files.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
from pathlib import Path
from typing import Any, List, Optional

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python3 -m chasles_client",
        description="Chasles motion planning client (gRPC chasles.v1.Planning). Requests are "
                    "protobuf JSON files such as examples/requests/*.json.",
        epilog="exit status: 0 ok, 1 failed (RPC error or no trajectory), 2 bad arguments or files")
    parser.add_argument("--server", default=os.environ.get("CHASLES_SERVER", "127.0.0.1:50051"),
                        help="server address, or several replicas separated by commas (balanced round-robin, "
                             "idempotent calls retried on UNAVAILABLE) (default $CHASLES_SERVER or 127.0.0.1:50051)")
    parser.add_argument("--tls-ca", metavar="FILE", help="use TLS; trust server certificates signed by this CA (PEM)")
    parser.add_argument("--tls-cert", metavar="FILE", help="client certificate (PEM) for mutual TLS; with --tls-key")
    parser.add_argument("--tls-key", metavar="FILE", help="the client certificate's private key (PEM)")
    parser.add_argument("--tls-server-name", metavar="NAME",
                        help="verify the server certificate for NAME (default: the --server host)")
    parser.add_argument("--token", help="bearer token (else --token-file, else $CHASLES_TOKEN); without TLS "
                                        "it is sent to loopback servers only")
    parser.add_argument("--token-file", metavar="FILE", help="read the bearer token from the first line of FILE")
    parser.add_argument("--timeout", type=float, default=None,
                        help="gRPC deadline [s] (default 10; plan/optimize: the request's budget + 30; "
                             "bench: none)")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    commands.add_parser("health", help="ask the server's gRPC health service (exit 0 when SERVING)")
    planners = commands.add_parser("planners", help="list planners with their parameters and ranges")
    planners.add_argument("--json", action="store_true", help="print them as JSON")

    for name, what in (("plan", "a chasles.v1.PlanRequest"), ("optimize", "a chasles.v1.OptimizeRequest")):
        command = commands.add_parser(name, help=f"send {what} (protobuf JSON) and print a summary")
        command.add_argument("request", metavar="REQUEST.json", help=f"{what} in protobuf JSON")
        command.add_argument("--method", choices=["topp", "collocation", "spline", "none"],
                             help="post-processing (overrides the request's)")
        command.add_argument("--plot", metavar="F", help="plot the trajectory to F (.png, .svg or .pdf)")
        command.add_argument("--csv", metavar="F", help="write the trajectory samples to F.csv")
        command.add_argument("--out", metavar="F", help="write the response as protobuf JSON to F")

    bench = commands.add_parser(
        "bench", help="benchmark planner configurations on problems (Benchmark RPC)",
        description="Runs problems x configurations x runs on the server. Problems and configurations "
                    "come from a chasles.v1.BenchmarkRequest file, or from --problem / --planner. "
                    "Ctrl-C stops the benchmark and keeps the finished runs.")
    bench.add_argument("request", metavar="BENCH.json", nargs="?",
                       help="a chasles.v1.BenchmarkRequest in protobuf JSON")
    bench.add_argument("--problem", metavar="PLAN.json", action="append", default=[],
                       help="a chasles.v1.PlanRequest file as a problem (repeatable; named after the file)")
    bench.add_argument("--planner", metavar="ID", action="append", default=[],
                       help="a planner id as a configuration (repeatable)")
    bench.add_argument("--runs", type=int, help="runs per problem and configuration (default 10)")
    bench.add_argument("--run-budget", type=float, help="planning budget of each run [s] (default 5)")
    bench.add_argument("--parallelism", type=int, help="runs at once (default: the server's threads)")
    bench.add_argument("--seed", type=int, help="run r is seeded seed + r (default 1)")
    bench.add_argument("--out", metavar="DIR",
                       help="write <problem>.log (OMPL logs), runs.csv and results.json into DIR")
    bench.add_argument("--plot", metavar="F", help="plot times and success rates to F (.png, .svg, .pdf)")
    bench.add_argument("--quiet", action="store_true", help="no progress line (none either when stderr is no terminal)")
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    args = _parser().parse_args(argv)
    from .errors import ChaslesError  # after parsing: --help works without the generated stubs

    try:
        return _COMMANDS[args.command](args)
    except ChaslesError as error:
        print(f"chasles_client: {error}", file=sys.stderr)
        return EXIT_FAILED
    except (OSError, ValueError, TypeError) as error:
        print(f"chasles_client: {error}", file=sys.stderr)
        return EXIT_USAGE


def _client(args: argparse.Namespace, default_timeout: Optional[float] = 10.0) -> Any:
    from .client import Client

    return Client(args.server, timeout=args.timeout if args.timeout is not None else default_timeout,
                  tls_ca=args.tls_ca, tls_cert=args.tls_cert, tls_key=args.tls_key,
                  tls_server_name=args.tls_server_name, token=_token(args))


def _token(args: argparse.Namespace) -> Optional[str]:
    """--token, else the first line of --token-file, else $CHASLES_TOKEN, else None."""
    if args.token:
        return args.token
    if args.token_file:
        try:
            lines = Path(args.token_file).read_text().splitlines()
        except OSError as error:
            raise ValueError(f"--token-file {args.token_file!r} cannot be read: {error.strerror}") from None
        token = lines[0].strip() if lines else ""
        if not token:
            raise ValueError(f"--token-file {args.token_file!r} holds no token on its first line")
        return token
    return os.environ.get("CHASLES_TOKEN", "").strip() or None


def _read_json(path: str) -> Any:
    try:
        return json.loads(Path(path).read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not JSON ({error})") from None


def _health(args: argparse.Namespace) -> int:
    with _client(args) as client:
        status = client.health()
    print(status)
    return EXIT_OK if status == "SERVING" else EXIT_FAILED


def _planners(args: argparse.Namespace) -> int:
    import dataclasses

    with _client(args) as client:
        planners = client.planners()
    if args.json:
        print(json.dumps([dataclasses.asdict(p) for p in planners], indent=1))
        return EXIT_OK
    for planner in planners:
        kinds = ", ".join(planner.robot_kinds)
        print(f"{planner.id}{' (optimizing)' if planner.optimizing else ''} [{kinds}]: {planner.description}")
        for p in planner.parameters:
            joint = " (per joint)" if p.per_joint else ""
            print(f"    {p.name}: {p.type} = {p.default:g} in [{p.min:g}, {p.max:g}]{joint} — {p.description}")
    return EXIT_OK


def _plan_or_optimize(args: argparse.Namespace) -> int:
    from google.protobuf import json_format

    from ._stubs import pb
    from .convert import enum_value
    from .plots import plot_trajectory

    data = _read_json(args.request)
    is_plan = args.command == "plan"
    request = pb.PlanRequest() if is_plan else pb.OptimizeRequest()
    try:
        json_format.ParseDict(data, request)
    except json_format.ParseError as error:
        raise ValueError(f"{args.request}: {error}") from None
    if args.method:
        options = request.trajectory if is_plan else request.options
        options.post_processing = enum_value(pb.TrajectoryOptions.PostProcessing, args.method, "--method")
    budget = request.time_budget or (5.0 if is_plan else 10.0)
    with _client(args, budget + 30.0) as client:
        result = client.plan_request(request) if is_plan else client.optimize_request(request)
    print(f"{result.outcome}: {result.message}")
    if result.trajectory is not None:
        traj = result.trajectory
        print(f"trajectory: {traj.dof} joints, {len(traj)} samples, {traj.duration:.4f} s; "
              f"max |qd|/v = {result.quality.get('max_velocity_ratio', 0.0):.3f}, "
              f"max |qdd|/a = {result.quality.get('max_acceleration_ratio', 0.0):.3f}; "
              f"post-processing {result.optimizer.get('used', '')}")
    if is_plan:
        timings = result.timings
        print(f"planning {timings['plan']:.3f} s, total {timings['total']:.3f} s on the server; "
              f"path {len(result.path)} waypoints, {result.statistics['path_length']:.3f} rad")
    if args.out:
        Path(args.out).write_text(json_format.MessageToJson(result.response))
        print(f"wrote {args.out}")
    if result.trajectory is not None:
        if args.csv:
            print(f"wrote {result.trajectory.write_csv(args.csv)}")
        if args.plot:
            plot_trajectory(result, path=args.plot, title=f"{Path(args.request).stem}: {result.outcome}")
            print(f"wrote {args.plot}")
    elif args.csv or args.plot:
        print("no trajectory: nothing plotted or written", file=sys.stderr)
    return EXIT_OK if result.success else EXIT_FAILED


def _bench(args: argparse.Namespace) -> int:
    from ._stubs import pb
    from .convert import benchmark_request, to_message

    if args.request:
        request = to_message(_read_json(args.request), pb.BenchmarkRequest, args.request)
        if not request.request_id:
            request.request_id = benchmark_request([], []).request_id
    elif not args.problem or not args.planner:
        raise ValueError("bench needs BENCH.json, or at least one --problem and one --planner")
    else:
        request = benchmark_request([], [])
    for path in args.problem:
        problem = request.problems.add(name=Path(path).stem)
        problem.request.CopyFrom(to_message(_read_json(path), pb.PlanRequest, path))
    for planner in args.planner:
        request.configs.add().planner.planner_id = planner
    for name, value in (("runs", args.runs), ("run_budget", args.run_budget),
                        ("parallelism", args.parallelism), ("seed", args.seed)):
        if value is not None:
            setattr(request, name, value)

    show_progress = not args.quiet and sys.stderr.isatty()

    def progress(p: Any) -> None:
        if show_progress:
            eta = f", about {p.eta:.0f} s left" if p.eta >= 0 else ""
            print(f"\r{p.done}/{p.total} runs, {p.running} running, {p.elapsed:.1f} s{eta}   ",
                  end="", file=sys.stderr, flush=True)

    client = _client(args, None)
    outcome: dict = {}

    def consume() -> None:
        try:
            outcome["result"] = client.benchmark_request(request, on_progress=progress)
        except BaseException as error:  # handed to the main thread
            outcome["error"] = error

    worker = threading.Thread(target=consume, name="chasles-benchmark", daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.2)
    except KeyboardInterrupt:
        print(f"\nstopping benchmark {request.request_id} (finished runs are kept)...", file=sys.stderr)
        client.stop_benchmark(request.request_id)
        worker.join()
    if show_progress:
        print(file=sys.stderr)
    client.close()
    if "error" in outcome:
        raise outcome["error"]
    result = outcome["result"]
    _print_summary(result)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for path in result.write_ompl_logs(out):
            print(f"wrote {path}")
        print(f"wrote {result.write_csv(out / 'runs.csv')}")
        print(f"wrote {result.write_json(out / 'results.json')}")
    if args.plot:
        from .plots import plot_benchmark

        plot_benchmark(result, path=args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK if any(run.solved for run in result.runs) else EXIT_FAILED


def _print_summary(result: Any) -> None:
    print(f"benchmark {result.request_id}: {result.runs_finished}/{result.runs_total} runs in "
          f"{result.wall_time:.1f} s, {result.parallelism} at once{' (stopped)' if result.stopped else ''}")
    header = f"{'configuration':<24} {'runs':>5} {'solved':>7} {'median s':>9} {'p95 s':>8} {'length':>8}"
    print(header)
    for s in result.summaries:
        print(f"{s.name:<24} {s.runs:>5} {100 * s.success_rate:>6.1f}% {s.median_time:>9.3f} "
              f"{s.p95_time:>8.3f} {s.median_length:>8.3f}")


_COMMANDS = {
    "health": _health,
    "planners": _planners,
    "plan": _plan_or_optimize,
    "optimize": _plan_or_optimize,
    "bench": _bench,
}
