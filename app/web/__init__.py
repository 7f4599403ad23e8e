"""The web teaching tool: FastAPI routes, the live simulation thread, the viser scene and GUI."""
