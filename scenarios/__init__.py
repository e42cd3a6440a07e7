"""Scene definitions and example scripts a user can copy and change."""
