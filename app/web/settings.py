"""Host, ports and report directory of ``pelvic-walk serve`` (pydantic-settings, env prefix
``PELVIC_WALK_``).

``PELVIC_WALK_HOST``, ``PELVIC_WALK_PORT``, ``PELVIC_WALK_VISER_PORT``,
``PELVIC_WALK_REPORT_DIR``, ``PELVIC_WALK_WORKERS``, ``PELVIC_WALK_SESSIONS``,
``PELVIC_WALK_ROBOTS_PER_WORKER``, ``PELVIC_WALK_DISPLAY_HZ``, ``PELVIC_WALK_DISPLAY_NICE``,
``PELVIC_WALK_IDLE_TIMEOUT``, ``PELVIC_WALK_SHARED_DEMO``, ``PELVIC_WALK_SESSIONS_PER_ADDRESS``,
``PELVIC_WALK_TRUSTED_PROXIES`` and ``PELVIC_WALK_INSTRUCTOR_TOKEN`` override the defaults;
command-line options override both. (The environment keeps the token out of the process list,
where ``--instructor-token`` shows.)
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from app.live.intent import DEFAULT_METHODS
from app.web.addresses import parse_trusted

# Robots a core keeps at 1.0x with the web process and 20 viewers on the same machine, measured
# with `serve --sessions private` + `loadtest --viewers 20` (docs/PERFORMANCE.md, "Capacity":
# 18 robots held on 2 cores, 21 did not): two thirds of that, so that a slower hour of the host
# (MuJoCo alone reads 50-77 x real time on the development machine) still keeps real time.
# `pelvic-walk bench`'s paced figure (11-22 robot loops a core) leaves out the viewers, the
# frames and the hand-offs.
ROBOTS_PER_CORE = 6
SESSION_ROBOTS = len(DEFAULT_METHODS)  # a session's robots by default (the demo's)
MAX_DEFAULT_WORKERS = 16  # each worker holds MuJoCo and Pinocchio (~130 MB resident)


def worker_layout(workers: int | None, robots_per_worker: int | None) -> tuple[int, int]:
    """(workers, robots each) from the options given (None: not given; 0 workers: the pool's
    one worker in threads of the web process, holding the capacity).

    The machine's capacity is ROBOTS_PER_CORE robots a core. The robots of one worker take
    turns on one core (Python's GIL), so by default there is one worker a core (at most
    MAX_DEFAULT_WORKERS) and the capacity is shared out over them; the pool spreads a
    session's robots over the workers and the operating system the workers over the cores.
    On a 2-core laptop: 2 workers x 6 robots, each started once (MuJoCo and Pinocchio, ~130
    MB and a second or two each), holding the demo and three private sessions of three.
    Given only ``workers``, they share the capacity out; given only ``robots_per_worker``,
    the capacity decides the workers. The demo's robots (SESSION_ROBOTS) always fit.
    """
    cores = os.cpu_count() or 1
    capacity = max(1, int(ROBOTS_PER_CORE * cores))
    if workers is None:
        if robots_per_worker is None:
            workers = min(cores, MAX_DEFAULT_WORKERS)
        else:
            workers = min(capacity // robots_per_worker, MAX_DEFAULT_WORKERS) or 1
    if robots_per_worker is None:
        n = max(workers, 1)
        robots_per_worker = max(-(-capacity // n), -(-SESSION_ROBOTS // n))  # ceil
    return workers, robots_per_worker


class Settings(BaseSettings):
    """Where the web tool listens (localhost unless told otherwise) and what ``/report`` shows."""

    model_config = SettingsConfigDict(env_prefix="PELVIC_WALK_")

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=1, le=65535)  # FastAPI (page, HTTP API, /docs)
    viser_port: int = Field(default=8080, ge=1, le=65535)  # viser (3-D scene and GUI)
    # None: the latest `pelvic-walk experiments --out DIR`, else the packaged reference report
    report_dir: Path | None = None
    # None for both: a session's robots per worker, ROBOTS_PER_CORE robots a core
    # (worker_layout); what a machine holds is measured with serve + loadtest
    # (docs/PERFORMANCE.md, "Capacity").
    # workers 0: the pool's one worker runs in threads of the web process (its in-process
    # engine), holding the capacity.
    workers: int | None = Field(default=None, ge=0, le=64)
    sessions: Literal["shared", "private"] = "shared"
    robots_per_worker: int | None = Field(default=None, ge=1, le=16)  # robots one worker runs
    display_hz: float = Field(default=20.0, ge=1.0, le=60.0)  # scene updates per second
    idle_timeout: float = Field(default=300.0, ge=5.0)  # [s] an API-opened session's life
    # how much lower than the workers the web and display threads run (Linux nice steps): when
    # the cores are short, the robots keep real time and the scene updates less often
    display_nice: int = Field(default=15, ge=0, le=19)
    # private mode: run the shared demo (it holds its robots' worker slots) or not (every slot
    # for the students' private sessions)
    shared_demo: bool = True
    # private mode: sessions one client address holds at most (its browsers' and scripts'
    # together), so no one client takes every seat; the server's own machine is not limited
    sessions_per_address: int = Field(default=1, ge=1, le=1000)
    # with it, only the instructor (the page opened with ?token=..., the API with
    # "Authorization: Bearer ...") changes the shared demo; SecretStr: never printed
    instructor_token: SecretStr | None = Field(default=None, min_length=1)
    # behind a reverse proxy: its addresses or networks, comma separated; from them (only)
    # X-Forwarded-For names the client, for the page, the API and the scene alike
    # (app.web.addresses)
    trusted_proxies: str = ""

    @field_validator("trusted_proxies", mode="before")
    @classmethod
    def _proxies(cls, value: object) -> object:
        """A list (``--trusted-proxy`` repeated) or a comma-separated string, each checked."""
        if isinstance(value, (list, tuple)):
            value = ",".join(str(v) for v in value)
        if isinstance(value, str):
            parse_trusted(value)  # ValueError names the bad entry
        return value

    @field_validator("instructor_token", mode="before")
    @classmethod
    def _empty_token_is_none(cls, value: object) -> object:
        """``PELVIC_WALK_INSTRUCTOR_TOKEN=`` (empty) means no instructor."""
        return None if value == "" else value

    @field_validator("report_dir", mode="before")
    @classmethod
    def _empty_is_default(cls, value: object) -> object:
        """``PELVIC_WALK_REPORT_DIR=`` (empty) means the default, not the working directory."""
        return None if value == "" else value
