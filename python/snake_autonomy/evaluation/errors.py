"""The one exception of the evaluation package: a message meant for the user, never a traceback."""


class EvaluationError(Exception):
    """Bad input (unreadable file, missing topic, no matching timestamps, too few pairs...).

    The message says what is wrong and what to try; the command line prints it and exits 1.
    """
