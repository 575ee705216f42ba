"""Application functions: identify, estimate, import, diagnose, reproduce, demo (used by the CLI and the nodes)."""
