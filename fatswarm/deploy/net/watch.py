"""`fatswarm dashboard` and the live view of a networked run: a Zenoh subscriber to the world's
state feeding the dashboard's renderers (deploy/view/dashboard.py), read-only."""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from rich.console import Console

from fatswarm.deploy.net.zconf import DEFAULT_SWARM, explain_zenoh_error, make_config
from fatswarm.deploy.view.dashboard import (
    MAX_DUTY,
    PROGRESS_EVERY,
    Frame,
    FrameSink,
    LiveView,
    ProgressLog,
    RateMeter,
    frame_from_state,
    save_svg,
)
from fatswarm.domain.outcome import ENDED, ExitCode, exit_code_for
from fatswarm.domain.wire import ProtocolError, check_swarm
from fatswarm.world.observers import WorldState
from fatswarm.world.protocol import state_key


def _open_session(connect: str, config: str | None = None) -> Any:
    import zenoh  # lazily: importing this module (the CLI's parser does) loads no zenoh

    if config is not None:  # Zenoh's own file (`--config`), e.g. a dashboard's from `secure`
        return zenoh.open(make_config("client", [connect], config_file=config))
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", f'["{connect}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


class StateWatcher:
    """Follows `fatswarm/<swarm>/world/state` in a thread and hands each new frame to a sink.

    It reads through `RingChannel(1)` (only the newest state is kept, DROP on the publisher), so a
    slow terminal loses frames, never rounds. Pass an open `session` or a `connect` endpoint.
    """

    def __init__(
        self,
        swarm: str,
        sink: FrameSink,
        *,
        session: Any = None,
        connect: str | None = None,
        fps: float = 5.0,
        max_rounds: int | None = None,
        stop_at_end: bool = False,
        svg: str | None = None,
        config: str | None = None,
    ) -> None:
        if session is None and connect is None:
            raise ValueError("StateWatcher needs an open session or a connect endpoint")
        self.swarm, self.sink, self.session, self.connect = swarm, sink, session, connect
        self.config = config  # Zenoh's configuration file for an own session (--config)
        self.period = 1.0 / fps
        self.max_rounds = max_rounds
        self.stop_at_end = stop_at_end
        self.svg = svg
        self.meter = RateMeter()
        self.latest: Frame | None = None
        self.refused: dict[str, int] = {}  # what the world refused or dropped, by kind (so far)
        self.ended = threading.Event()  # the run reached a final status
        self.finished = threading.Event()  # the thread stopped following
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="fatswarm-dashboard", daemon=True)
        self.error: BaseException | None = None

    def start(self) -> StateWatcher:
        self._thread.start()
        return self

    def _run(self) -> None:
        import zenoh  # lazily: importing this module (the CLI's parser does) loads no zenoh

        own = self.session is None
        try:
            session = (
                _open_session(self.connect, self.config)  # type: ignore[arg-type]
                if own
                else self.session
            )
        except Exception as exc:  # zenoh raises its own ZError; report it to the caller
            self.error = exc
            self.finished.set()
            return
        try:
            sub = session.declare_subscriber(state_key(self.swarm), zenoh.handlers.RingChannel(1))
            try:
                self._show_states(sub)
            finally:
                sub.undeclare()
        except Exception as exc:  # a failing display must never take the run down with it
            self.error = exc
        finally:
            if own:
                session.close()
            self.finished.set()

    def _show_states(self, sub: Any) -> None:
        """Hand the newest state's frame to the sink until stopped (or, with `stop_at_end`, until
        the run ends)."""
        while True:
            stopping = self._stop.is_set()  # then take one last look, and leave
            frame = self._frame_of(sub.try_recv())
            if stopping:
                break  # the sink shows `latest` when it closes
            if frame is None:
                self._stop.wait(self.period)
                continue
            began = time.monotonic()
            self.sink.show(frame)
            busy = time.monotonic() - began
            if self.stop_at_end and frame.status in ENDED:
                break
            # drawing may take at most 1/MAX_DUTY of the time: the swarm needs the CPU
            self._stop.wait(max(self.period, busy * (MAX_DUTY - 1)))

    def _frame_of(self, sample: Any) -> Frame | None:
        """The frame of a state sample, kept as `latest`; None if no sample or not a state."""
        if sample is None:
            return None
        try:
            state = WorldState.decode(sample.payload.to_bytes())
        except ProtocolError:
            return None
        self.refused = state.refused or self.refused
        rate = self.meter.add(time.monotonic(), state.round)
        if rate is None and self.latest is not None:
            rate = self.latest.rounds_per_second
        frame = frame_from_state(state, rate, self.max_rounds)
        self.latest = frame
        if frame.status in ENDED:
            self.ended.set()
        return frame

    def stop(self, final: Frame | WorldState | None = None) -> None:
        """Stop following; leave the final frame (given, else the last seen) on screen and in SVG.

        Pass the final state when you have it: the last published one may have been dropped.
        """
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)
        last_rate = self.latest.rounds_per_second if self.latest is not None else None
        if final is not None and not isinstance(final, Frame):
            final = frame_from_state(final, last_rate, self.max_rounds)
        elif final is not None and final.rounds_per_second is None:
            final = replace(final, rounds_per_second=last_rate)
        frame = final or self.latest
        self.sink.close(frame)
        if self.svg and frame is not None:
            save_svg(frame, self.svg)


def watch(
    swarm: str,
    *,
    session: Any = None,
    connect: str | None = None,
    dashboard: bool | None = None,
    quiet: bool = False,
    svg: str | None = None,
    every: int = PROGRESS_EVERY,
    max_rounds: int | None = None,
    console: Console | None = None,
    progress: Callable[[str], None] | None = None,
) -> StateWatcher:
    """Start showing a running swarm: the live dashboard, else progress lines (none if `quiet`)
    passed to `progress` (default: printed on standard output).

    `dashboard=None` picks by whether standard output is a terminal. Call `.stop(final)` at the end.
    """
    if dashboard is None:
        dashboard = sys.stdout.isatty()
    sink: FrameSink
    if dashboard:
        sink = LiveView(console)
    else:
        sink = ProgressLog(out=(lambda line: None) if quiet else progress, every=every)
    try:
        watcher = StateWatcher(
            swarm, sink, session=session, connect=connect, max_rounds=max_rounds, svg=svg
        )
        return watcher.start()
    except BaseException:
        sink.close(None)
        raise


def follow(
    args: argparse.Namespace,
    swarm: str,
    *,
    session: Any = None,
    connect: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> StateWatcher:
    """What `fatswarm run` calls once the router is up: the live view or the progress log.

    Reads `--no-dashboard`, `--json`, `--svg`, `--max-rounds` and `--quiet` from `args`; the
    dashboard is shown only when standard output is a terminal and not kept for `--json`.
    Progress lines go to `progress` (default: standard output). Call `.stop(final)` at the end.
    """
    plain = getattr(args, "no_dashboard", False) or getattr(args, "json", False)
    return watch(
        swarm,
        session=session,
        connect=connect,
        dashboard=not plain and sys.stdout.isatty(),
        quiet=getattr(args, "quiet", False),
        svg=getattr(args, "svg", None),
        max_rounds=getattr(args, "max_rounds", None),
        progress=progress,
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Flags of `fatswarm dashboard`."""
    p.add_argument(
        "--connect",
        metavar="ENDPOINT",
        required=True,
        help="the Zenoh router of the swarm, e.g. tcp/127.0.0.1:7447",
    )
    p.add_argument("--swarm", default=DEFAULT_SWARM, help=f"swarm name (default {DEFAULT_SWARM!r})")
    p.add_argument(
        "--config",
        metavar="FILE",
        default=None,
        help="Zenoh's own configuration file, e.g. dashboard-0.json5 of `fatswarm secure` (TLS); "
        "its mode, multicast scouting and endpoint are this command's",
    )
    p.add_argument(
        "--exit-at-end", action="store_true", help="exit when the run ends (default: at Ctrl-C)"
    )
    p.add_argument(
        "--no-dashboard", action="store_true", help="print progress lines instead of the live view"
    )
    p.add_argument(
        "--every", type=int, default=50, metavar="K", help="progress lines: one every K rounds"
    )
    p.add_argument("--svg", metavar="PATH", help="save the last frame shown as SVG on exit")


def main(args: argparse.Namespace) -> int:
    """`fatswarm dashboard`: follow a running swarm read-only until Ctrl-C (or its end)."""
    try:
        check_swarm(args.swarm)
        if args.config is not None:  # a bad file is one line, before any wait
            make_config("client", [args.connect], config_file=args.config)
    except ValueError as exc:
        print(f"fatswarm dashboard: {exc}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    if args.every < 1:
        print("fatswarm dashboard: --every must be at least 1", file=sys.stderr)
        return ExitCode.BAD_INPUT
    dashboard = not args.no_dashboard and sys.stdout.isatty()
    sink: FrameSink = LiveView() if dashboard else ProgressLog(every=args.every)
    watcher = StateWatcher(
        args.swarm,
        sink,
        connect=args.connect,
        stop_at_end=args.exit_at_end,
        svg=args.svg,
        config=args.config,
    )
    watcher.start()
    try:
        while not watcher.finished.wait(0.2):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        watcher.stop()
    if watcher.error is not None:
        reason = explain_zenoh_error(watcher.error)
        print(f"fatswarm dashboard: cannot follow {args.connect}: {reason}", file=sys.stderr)
        return ExitCode.BAD_INPUT
    last = watcher.latest
    if last is None or last.status not in ENDED:
        return ExitCode.NOT_FORMED
    return exit_code_for(last.status, last.collisions_total)  # as `fatswarm run`: 3 if collided
