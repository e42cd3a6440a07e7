"""A scene as an SSP package for other tools (two instances, or one per component)."""
