"""Examples a user copies and changes."""
