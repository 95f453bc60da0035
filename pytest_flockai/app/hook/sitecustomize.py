"""Start-up hook of an app flown by ``pytest_flockai.app.run`` (on its PYTHONPATH only).

An unchanged MAVSDK-Python or pymavlink program names PX4 SITL's UDP port 14540 and
MAVSDK's gRPC port 50051; two such apps tested side by side would command each
other's drone. This hook rewrites those two ports, in ``mavsdk.System`` and
``pymavlink.mavutil.mavlink_connection``, to the run's own (``FLOCKAI_MAVLINK_PORT``,
``FLOCKAI_GRPC_PORT``) when the modules are imported; nothing else changes. A
``sitecustomize`` further down the path still runs.
"""

import importlib.abc
import importlib.machinery
import os
import re
import sys

_PORT = os.environ.get("FLOCKAI_MAVLINK_PORT")
_GRPC = os.environ.get("FLOCKAI_GRPC_PORT")


def _url(address):
    if _PORT and isinstance(address, str):
        return re.sub(r":14540\b", f":{_PORT}", address)
    return address


def _patch_mavsdk(mod):
    cls = mod.System
    init, connect = cls.__init__, cls.connect

    def __init__(self, mavsdk_server_address=None, port=50051, *args, **kw):
        if mavsdk_server_address is None and port == 50051 and _GRPC:
            port = int(_GRPC)
        init(self, mavsdk_server_address, port, *args, **kw)

    async def _connect(self, system_address=None):
        if system_address is None and _PORT:
            system_address = f"udpin://0.0.0.0:{_PORT}"
        return await connect(self, _url(system_address))

    cls.__init__, cls.connect = __init__, _connect


def _patch_mavutil(mod):
    conn = mod.mavlink_connection

    def mavlink_connection(device, *args, **kw):
        return conn(_url(device), *args, **kw)

    mod.mavlink_connection = mavlink_connection


_PATCHES = {"mavsdk.system": _patch_mavsdk, "pymavlink.mavutil": _patch_mavutil}


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        patch = _PATCHES.get(name)
        if patch is None:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            patch(module)

        spec.loader.exec_module = exec_module
        return spec


sys.meta_path.insert(0, _Finder())


def _chain():
    """Run the next ``sitecustomize`` on the path, if there is one."""
    here = os.path.dirname(os.path.abspath(__file__))
    for entry in sys.path:
        if os.path.abspath(entry or ".") == here:
            continue
        spec = importlib.machinery.PathFinder.find_spec("sitecustomize", [entry])
        if spec is not None and spec.loader is not None:
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return


import importlib.util  # noqa: E402

_chain()
