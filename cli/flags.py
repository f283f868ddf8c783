# SPDX-License-Identifier: GPL-3.0-or-later
"""The planning flags, derived from the settings table (``api.SETTINGS``), so that the CLI
offers what the panel shows and the API accepts: a flag per float or choice setting, or the
setting's switches (--foot-lock / --no-foot-lock). A flag not given is None: the scene's
setting is used. Ranges are checked by the API (one refusal, worded alike, for every door);
the help states them."""

import argparse

from .. import api

BY_NAME = {s.name: s for s in api.SETTINGS}
PLANNING = tuple(BY_NAME)  # the flags of plan and crowd
WEIGHTS = tuple(s.name for s in api.SETTINGS if s.kind is float)  # a layout spec's, too


def add_settings(p, names=PLANNING):
    """Add the flags of the settings ``names`` to parser ``p``, in the table's order."""
    for s in api.SETTINGS:
        if s.name not in names:
            continue
        if s.switches:
            _add_switches(p, s)
        elif s.kind is float:
            p.add_argument(
                _words(s.flag or s.name),
                dest=s.name,
                type=float,
                help=_help(f"{_plain(s.help)}: {_range(s)}", s),
            )
        elif s.kind is str:
            ways = "; ".join(f"{v}: {_plain(tip)}" for v, _, tip in s.choices)
            p.add_argument(
                _words(s.flag or s.name), dest=s.name, choices=s.values, help=_help(ways, s)
            )
        else:
            p.add_argument(
                _words(s.flag or s.name),
                dest=s.name,
                action=argparse.BooleanOptionalAction,
                help=_help(_plain(s.help), s),
            )


def _add_switches(p, s):
    """Mutually exclusive flags, each storing its value in ``s.name``; the first one's help
    tells the default."""
    g = p.add_mutually_exclusive_group()
    tips = {v: tip for v, _, tip in s.choices}  # a choice's own help
    for i, (value, words, text) in enumerate(s.switches):
        text = _plain(text or tips.get(value, s.help))
        g.add_argument(
            _words(words),
            dest=s.name,
            action="store_const",
            const=value,
            help=_help(text, s) if i == 0 else _escape(text),
        )


def _words(name):
    return "--" + name.replace("_", "-")


def _plain(text):
    """A panel's tooltip as the help of a flag (lower-case start, as argparse's own)."""
    return text[:1].lower() + text[1:]


def _range(s):
    unit = " of metres" if s.unit == "m" else ""
    return f"a number{unit} from {s.minimum:g} to {s.maximum:g}"


def _shown(s, value):
    if s.kind is bool:
        return "on" if value else "off"
    if s.kind is float:
        return f"{value:g}" + (" m" if s.unit == "m" else "")
    return value


def _help(text, s):
    return _escape(
        f"{text}; default: the scene's {s.label} setting (whose own default is "
        f"{_shown(s, s.default)})"
    )


def _escape(text):
    return text.replace("%", "%%")  # argparse formats help with %
