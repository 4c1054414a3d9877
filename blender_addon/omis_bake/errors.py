"""Exceptions of the add-on (no bpy here)."""


class BakeError(Exception):
    """The bake cannot run or failed; the message is meant for the artist."""


class Cancelled(Exception):
    """The bake was cancelled (Esc, or a progress callable returning False); nothing was
    written."""
