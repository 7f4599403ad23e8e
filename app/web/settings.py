"""Host, ports and report directory of ``pelvic-walk serve`` (pydantic-settings, env prefix
``PELVIC_WALK_``).

``PELVIC_WALK_HOST``, ``PELVIC_WALK_PORT``, ``PELVIC_WALK_VISER_PORT``,
``PELVIC_WALK_REPORT_DIR``, ``PELVIC_WALK_WORKERS``, ``PELVIC_WALK_SESSIONS``,
``PELVIC_WALK_ROBOTS_PER_WORKER``, ``PELVIC_WALK_DISPLAY_HZ``, ``PELVIC_WALK_DISPLAY_NICE``
and ``PELVIC_WALK_IDLE_TIMEOUT`` override the defaults; command-line options override both.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    """Where the web tool listens (localhost unless told otherwise) and what ``/report`` shows."""

    model_config = SettingsConfigDict(env_prefix="PELVIC_WALK_")

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=1, le=65535)  # FastAPI (page, HTTP API, /docs)
    viser_port: int = Field(default=8080, ge=1, le=65535)  # viser (3-D scene and GUI)
    # None: the latest `pelvic-walk experiments --out DIR`, else the packaged reference report
    report_dir: Path | None = None
    workers: int | None = Field(default=None, ge=0, le=64)  # None: one per core; 0: in-process
    sessions: Literal["shared", "private"] = "shared"
    robots_per_worker: int = Field(default=2, ge=1, le=16)  # robots one worker runs at once
    display_hz: float = Field(default=20.0, ge=1.0, le=60.0)  # scene updates per second
    idle_timeout: float = Field(default=300.0, ge=5.0)  # [s] an API-opened session's life
    # how much lower than the workers the web and display threads run (Linux nice steps): when
    # the cores are short, the robots keep real time and the scene updates less often
    display_nice: int = Field(default=15, ge=0, le=19)

    @field_validator("report_dir", mode="before")
    @classmethod
    def _empty_is_default(cls, value: object) -> object:
        """``PELVIC_WALK_REPORT_DIR=`` (empty) means the default, not the working directory."""
        return None if value == "" else value
