"""Host and ports of ``pelvic-walk serve`` (pydantic-settings, env prefix ``PELVIC_WALK_``).

``PELVIC_WALK_HOST``, ``PELVIC_WALK_PORT`` and ``PELVIC_WALK_VISER_PORT`` override the
defaults; command-line options override both.
"""

from __future__ import annotations

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    """Where the web tool listens. Bound to localhost unless told otherwise."""

    model_config = SettingsConfigDict(env_prefix="PELVIC_WALK_")

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=1, le=65535)  # FastAPI (page, HTTP API, /docs)
    viser_port: int = Field(default=8080, ge=1, le=65535)  # viser (3-D scene and GUI)
