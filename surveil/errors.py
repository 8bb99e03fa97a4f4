"""The project's exception hierarchy. Only ``surveil.cli`` turns these into messages and exit
codes; everything else raises them with a message that says what is wrong, where, and how to
fix it."""


class SurveilError(Exception):
    """Base class of every error surveil raises on purpose."""


class InputError(SurveilError):
    """An input file (calibration, recording, video, ground truth, MCAP) cannot be used."""


class ConfigError(SurveilError):
    """A configuration or scenario file is invalid."""


class RuleError(ConfigError):
    """An activity rule file is invalid."""
