"""Path options in the space form (``--flockai-baseline PATH``) must not move pytest's rootdir.

pytest finds the rootdir and the ini file before it loads plugins from entry
points, so at that moment ``--flockai-baseline`` is an unknown option and the
``PATH`` after it is taken as a test path: with a ``PATH`` outside the
project, the rootdir moves to a common ancestor, the project's ini file is
not read and every node id changes (so no baseline entry matches and the gate
lets every regression through). The ``=`` form (``--flockai-baseline=PATH``)
never had the problem.

``redo_setup`` runs in ``pytest_load_initial_conftests``, once the plugin's
options are known and the test paths are parsed right: when a path option was
written in the space form and the rootdir or the ini file found without its
value differs, the rootdir, the ini file and its ``addopts`` are set as they
would have been with the ``=`` form. Where this pytest version does not allow
it, the run stops with a UsageError asking for the ``=`` form, so the gate
never runs silently on the wrong node ids.
"""

from __future__ import annotations

import inspect
import os
from pathlib import Path

import pytest
from _pytest.config import findpaths  # private: pytest has no public API for the rootdir

from .options import path_dests


def space_form_values(args, config) -> list[str]:
    """The values of the plugin's path options written as ``--opt VALUE``."""
    flags = {f"--{d.replace('_', '-')}" for d in path_dests()}
    out = []
    for i, a in enumerate(args[:-1]):
        if str(a) in flags:
            out.append(str(args[i + 1]))
    return out


def redo_setup(early_config, args) -> None:
    values = space_form_values(list(args), early_config)
    if not values:
        return
    ns = early_config.known_args_namespace
    try:
        found = _determine(findpaths.determine_setup, ns, early_config)
        rootpath, inipath, inicfg = found[0], found[1], found[2]
        if rootpath == early_config.rootpath and inipath == early_config.inipath:
            return
        old_cut = str(early_config.inipath.parent if early_config.inipath is not None
                      else early_config.rootpath)
        early_config._rootpath, early_config._inipath = rootpath, inipath
        if hasattr(early_config, "_inicfg"):
            early_config._inicfg = inicfg
        else:                                          # pytest < 8.4
            early_config.inicfg = inicfg
        if len(found) > 3 and hasattr(early_config, "_ignored_config_files"):
            early_config._ignored_config_files = found[3]
        early_config._inicache.clear()
        early_config._parser.extra_info["rootdir"] = str(rootpath)
        early_config._parser.extra_info["inifile"] = str(inipath)
        if ns.confcutdir == old_cut:
            ns.confcutdir = str(inipath.parent if inipath is not None else rootpath)
        addopts = list(early_config.getini("addopts") or [])
        if addopts:
            args[:] = addopts + list(args)
            early_config.known_args_namespace = early_config._parser.parse_known_args(
                args, namespace=ns)
    except (AttributeError, TypeError) as exc:   # pragma: no cover - old pytest
        raise pytest.UsageError(
            f"pytest-flockai: {' '.join(values)} was read by pytest as a test path while it "
            f"looked for the rootdir ({exc}); write the option as --flockai-...=PATH") from None


def _determine(determine_setup, ns, config):
    kwargs = {"inifile": ns.inifilename, "override_ini": getattr(ns, "override_ini", None),
              "args": list(ns.file_or_dir), "rootdir_cmd_arg": ns.rootdir or None,
              "invocation_dir": config.invocation_params.dir}
    params = inspect.signature(determine_setup).parameters
    return determine_setup(**{k: v for k, v in kwargs.items() if k in params})


def param_id(config, val) -> str | None:
    """The id of a parametrized value that is an absolute path (a str; pytest
    names Path objects ``argname0`` itself): relative to the rootdir, with ``/``,
    so node ids and baseline entries are the same in every checkout. None
    (pytest's own id) for anything else."""
    if not isinstance(val, str) or not os.path.isabs(val):
        return None
    try:
        return Path(val).relative_to(config.rootpath).as_posix()
    except ValueError:
        return None
