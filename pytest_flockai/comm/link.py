"""Moved to ``pytest_flockai.comm.radio``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "C_LIGHT": "pytest_flockai.comm.radio.C_LIGHT",
    "ConfigError": "pytest_flockai.comm.radio.ConfigError",
    "LINKS": "pytest_flockai.comm.radio.LINKS",
    "Link": "pytest_flockai.comm.radio.Link",
    "RadioLinear": "pytest_flockai.comm.radio.RadioLinear",
    "RadioStates": "pytest_flockai.comm.radio.RadioStates",
    "Transfer": "pytest_flockai.comm.radio.Transfer",
    "close_matches": "pytest_flockai.comm.radio.close_matches",
    "link": "pytest_flockai.comm.radio.link",
    "links": "pytest_flockai.comm.radio.links",
})
