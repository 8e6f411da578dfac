"""The library's options in the command line's words: ``rate=HZ`` becomes ``--rate HZ``.

The library names an option in its messages and notes as the keyword argument a caller
passes, with its value when the message gives one (``rate=HZ``, ``gaps="fill"``,
``uniform=True``, ``scale={'gx': FACTOR}``, ``topic=``); :func:`with_flags` rewrites them as
the flags that set them, for the errors, notes and warnings the command line prints.  A
message reads right in both places: a library user is told what to pass to
:func:`fosmodel.io.load_record`, a command-line user what to type.
"""

from __future__ import annotations

import re

# A keyword must start a word: not inside a path (``/rate=1/``), a name or a quoted value.
_START = r"(?<![\w.'\"/=-])"
#: The options the library names, by their keyword; each becomes ``--`` and its name.
KEYWORDS = ("columns", "rate", "scale", "uniform", "outliers", "gaps", "topic",
            "temperature_topic", "loop_split", "temperature", "degree", "instance", "gyro_id",
            "accel_id", "start", "stop")
# Spellings with a value that the flag spells otherwise, tried before the bare keywords.
_SPELLINGS = (
    (re.compile(_START + r"train_s= and evaluate_s="), "--split"),
    (re.compile(_START + r"horizon_s="), "--horizon"),
    (re.compile(_START + r"min_span_c="), "--min-span "),
    (re.compile(_START + r"head_s="), "--head "),
    (re.compile(_START + r"block_s="), "--block "),
    (re.compile(_START + r"uniform=True\b"), "--uniform"),
    (re.compile(_START + r"static_only=True\b"), "--static-only"),
    (re.compile(_START + r"gaps=([\"'])(fill|segments)\1"), r"--\2"),
    (re.compile(_START + r"scale=\{([\"'])(.*?)\1: (.*?)\}"), r"--scale \2=\3"),
    (re.compile(_START + r"units=\{([\"'])(.*?)\1: (.*?)\}"), r"--units \2=\3"),
)
# outliers="clip" or "drop", outliers="clip" (or "keep"): the flag takes the values bare
_OUTLIERS = re.compile(_START + r"outliers=([\"']\w+[\"'](?: \(?or [\"']\w+[\"']\)?)*)")
_BARE = re.compile(_START + r"(" + "|".join(KEYWORDS) + r")=([\w'\"]?)")


def with_flags(text: str) -> str:
    """Return ``text`` with every option the library names written as its flag.

    Examples
    --------
    >>> with_flags("pass gaps='fill' to interpolate across them, or rate=HZ")
    'pass --fill to interpolate across them, or --rate HZ'
    >>> with_flags("use outliers='clip' (or 'keep'); choose one with topic=: /a, /b")
    'use --outliers clip (or keep); choose one with --topic: /a, /b'
    """
    for pattern, flag in _SPELLINGS:
        text = pattern.sub(flag, text)
    text = _OUTLIERS.sub(lambda m: "--outliers " + re.sub(r"[\"']", "", m.group(1)), text)
    return _BARE.sub(lambda m: "--" + m.group(1).replace("_", "-")
                     + (" " + m.group(2) if m.group(2) else ""), text)
