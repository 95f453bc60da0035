"""The key that authenticates flight-cache entries (an HMAC-SHA256 over each entry).

Entries are sealed with a secret key, so that whoever can write the cache folder
(a CI cache restored from another branch or pull request, a shared runner, a
copied folder) but does not hold the key cannot make an entry the cache trusts.

Where the key comes from, first match:

1. ``FLOCKAI_CACHE_KEY`` (the environment): the key itself, e.g. a CI secret;
2. ``FLOCKAI_CACHE_KEY_FILE``: a file holding the key;
3. a random key kept in ``$XDG_CONFIG_HOME/pytest-flockai/cache-key`` (default
   ``~/.config/...``), created on first use with mode 0600: entries are then trusted
   only by this user on this machine;
4. none can be read or created: a key of this process only (nothing is reused
   across runs; ``source`` says so).

An entry sealed under another key, or under none (an older format), is flown again
and rewritten, and the run reports it ("not authentic").
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

from ..errors import ConfigError

ENV_KEY = "FLOCKAI_CACHE_KEY"
ENV_KEY_FILE = "FLOCKAI_CACHE_KEY_FILE"
_PROCESS_KEY = secrets.token_bytes(32)
_WARNED: set = set()


class CacheWarning(UserWarning):
    """The flight cache could not be written, or works with less than asked (the run
    goes on): a key of this process only, an entry not stored."""


@dataclass(frozen=True)
class CacheKey:
    """A secret (never shown) and where it came from (shown in ``flockai cache info``)."""

    secret: bytes
    source: str

    def mac(self, *parts: bytes) -> str:
        """HMAC-SHA256 (hex) of ``parts``, each length-prefixed (no two splits collide)."""
        h = hmac.new(self.secret, digestmod=hashlib.sha256)
        for p in parts:
            h.update(len(p).to_bytes(8, "big"))
            h.update(p)
        return h.hexdigest()

    def verify(self, mac: object, *parts: bytes) -> bool:
        """True when ``mac`` is this key's HMAC of ``parts`` (constant-time compare)."""
        return isinstance(mac, str) and hmac.compare_digest(mac, self.mac(*parts))

    def __repr__(self) -> str:
        return f"CacheKey(source={self.source!r})"


def key_file() -> Path:
    """Where the per-user key is kept (``FLOCKAI_CACHE_KEY_FILE`` or the config folder)."""
    named = os.environ.get(ENV_KEY_FILE)
    if named:
        return Path(os.path.expanduser(named))
    base = os.environ.get("XDG_CONFIG_HOME") or os.path.join(os.path.expanduser("~"), ".config")
    return Path(base) / "pytest-flockai" / "cache-key"


def from_secret(secret: object) -> CacheKey:
    """A key given in code (``FlightCache(dir, key=b"...")``)."""
    if isinstance(secret, CacheKey):
        return secret
    if isinstance(secret, str):
        secret = secret.encode("utf-8")
    if not isinstance(secret, (bytes, bytearray)) or not secret:
        raise ConfigError(f"flight cache: key = {secret!r} is not allowed; expected a "
                          f"non-empty str or bytes")
    return CacheKey(bytes(secret), "given in code")


def default_key() -> CacheKey:
    """The key of this environment (see the module doc for the order)."""
    env = os.environ.get(ENV_KEY)
    if env:
        return CacheKey(env.encode("utf-8"), f"${ENV_KEY}")
    path = key_file()
    secret = _read_or_create(path)
    if secret is not None:
        return CacheKey(secret, str(path))
    why = _unusable(path)
    if str(path) not in _WARNED:
        _WARNED.add(str(path))
        warnings.warn(f"pytest-flockai: the flight cache key file {path} {why}; entries are "
                      f"sealed with a key of this process only, so no entry is reused by the "
                      f"next run. Make it a private regular file, or set {ENV_KEY}",
                      CacheWarning, stacklevel=2)
    return CacheKey(_PROCESS_KEY, f"this process only ({path} {why})")


def _unusable(path: Path) -> str:
    """Why the key file cannot be used, in a few words."""
    try:
        st = os.lstat(path)
    except OSError as exc:
        return f"cannot be read or created ({exc.strerror or exc})"
    if stat.S_ISLNK(st.st_mode):
        return "is a symlink (never followed: whoever controls its target would hold the key)"
    if not stat.S_ISREG(st.st_mode):
        return "is not a regular file"
    return "cannot be read, or is empty"


def _read_or_create(path: Path) -> bytes | None:
    """The key in ``path``; made first when there is none. Several processes may start
    at once (pytest-xdist's workers on a first run): the key file appears whole or not at
    all (written to a private file beside it, then hard-linked to its name, which never
    replaces one that is there), so each reads the one key that won. Where hard links
    are not supported, the file is made in place and a reader that finds it empty reads
    again for up to ``_SETTLE_S``."""
    try:
        return _read(path)
    except FileNotFoundError:
        pass
    except OSError:
        return None
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        _create(path)
    except FileExistsError:
        pass                                 # another process made it first: read theirs
    except OSError:
        return None
    deadline = time.monotonic() + _SETTLE_S
    while True:
        try:
            data = _read(path)
        except OSError:
            return None
        if data is not None or time.monotonic() >= deadline or not path.is_file():
            return data
        time.sleep(0.01)                     # made in place by another process: not written yet


#: s a reader waits for a key file another process made in place to be written
_SETTLE_S = 1.0


def _create(path: Path) -> None:
    """Write a new random key to ``path``, atomically; FileExistsError when there is one."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(secrets.token_hex(32) + "\n")
        try:
            os.link(tmp, path)               # appears whole; never replaces another's key
        except FileExistsError:
            raise
        except OSError:                      # no hard links here: make it in place
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
            with os.fdopen(fd, "w") as fh, open(tmp) as src:
                fh.write(src.read())
    finally:
        os.unlink(tmp)


def _read(path: Path) -> bytes | None:
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            return None
        data = fh.read(4096).strip()
    return data or None


__all__ = ["ENV_KEY", "ENV_KEY_FILE", "CacheKey", "CacheWarning", "default_key", "from_secret", "key_file"]
