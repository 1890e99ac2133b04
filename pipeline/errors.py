"""The one exception type for bad input: its message is the whole one-line error shown to users."""


class ConfigError(ValueError):
    """A configuration or input file value that cannot be used; the message names key and value."""
