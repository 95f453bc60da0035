"""Where a labelled image set keeps its images and labels: the layouts teams use.

``find_labelset(path, fmt="auto", split=None)`` returns a ``LabelSet``: the
images (sorted by file name), the label format and each image's label file.
Layouts read:

- **flat**: images and their labels in one folder: ``annotations.json`` /
  ``instances*.json`` (COCO), or one ``<image stem>.txt`` per image (YOLO; names in
  ``classes.txt`` or ``data.yaml``);
- **images/ + labels/** (YOLO, Ultralytics): ``<root>/images/[<split>/]*.jpg`` with
  ``<root>/labels/[<split>/]<stem>.txt``; ``images/`` + a COCO file in the root or
  in ``annotations/``;
- **Ultralytics data.yaml** (the file itself, or a folder holding it with ``train:``
  / ``val:`` / ``test:`` keys): ``path:`` (the root, relative to the file), the
  split's image folder and ``names:``; labels where Ultralytics looks for them
  (the last ``images`` in the path replaced by ``labels``). ``split``: the key
  (default ``val``, else ``test``, else ``train``);
- **VisDrone-DET**: ``<root>/images/*.jpg`` with ``<root>/annotations/<stem>.txt``.

A folder with a ``split`` sub-folder (``images/val``) is read when ``split`` names it
or when it is the only one.

Nothing is guessed: a folder with several COCO files (``instances_train.json`` and
``instances_val.json``) is read when ``split`` picks one (``instances_<split>*.json``)
or ``annotations=`` names the file itself, else it is a ``ConfigError`` listing them;
a label path that exists but is not a regular file (a folder, a FIFO, a link to a
device) is a ``ConfigError`` naming it (it would be read as "no objects").
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field

from ..errors import ConfigError

IMAGE_EXT = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
FORMATS = ("auto", "coco", "yolo", "visdrone")
SPLITS = ("val", "test", "train")


@dataclass
class LabelSet:
    """Images and labels of one set (see the module docstring)."""

    root: str
    images: list
    fmt: str | None = None                  # "coco", "yolo", "visdrone"; None: no labels
    label_files: list = field(default_factory=list)   # per image (yolo, visdrone) or None
    coco_file: str | None = None
    names: tuple | None = None               # class names the set declares (YOLO)
    label_dir: str | None = None             # where YOLO / VisDrone labels live


def list_images(folder: str) -> list:
    return sorted(os.path.join(folder, f) for f in os.listdir(folder)
                  if f.lower().endswith(IMAGE_EXT))


def regular(path, where) -> bool:
    """Whether a regular file (or a link to one) is at ``path``; False when nothing is
    there; ConfigError naming it when something else is (a folder, a FIFO, a device)."""
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        if os.path.islink(path):
            raise ConfigError(f"{where}: label file {os.fspath(path)!r} is a link to nothing "
                              f"({os.readlink(path)!r} does not exist)") from None
        return False
    except OSError as exc:
        raise ConfigError(f"{where}: label file {os.fspath(path)!r} cannot be read: "
                          f"{exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        what = "a folder" if stat.S_ISDIR(st.st_mode) else "a FIFO, a device or a socket"
        raise ConfigError(f"{where}: label file {os.fspath(path)!r} is not a regular file "
                          f"({what}); labels are read from regular files only")
    return True


def read_text(path, where) -> str:
    """A label file's text (UTF-8); ConfigError naming the file when it is not."""
    regular(path, where)
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{where}: label file {os.fspath(path)!r} is not UTF-8 text (byte "
                          f"{exc.start}: {exc.object[exc.start:exc.start + 1]!r})") from None
    except OSError as exc:
        raise ConfigError(f"{where}: label file {os.fspath(path)!r} cannot be read: "
                          f"{exc.strerror or exc}") from None


def find_labelset(path, *, fmt="auto", split=None, where: str = "annotations") -> LabelSet:
    """The LabelSet at ``path`` (a folder or a data.yaml); ConfigError when nothing is
    there. ``fmt`` may also be the path of a COCO .json file: that file is read."""
    chosen = None
    if isinstance(fmt, (str, os.PathLike)) and os.fspath(fmt).lower().endswith(".json"):
        chosen = os.fspath(fmt)
        if not regular(chosen, where):
            raise ConfigError(f"{where}: annotations = {chosen!r}: no such COCO file")
        fmt = "coco"
    if fmt is not None and fmt not in FORMATS:
        raise ConfigError(f"{where}: annotations = {fmt!r} is not allowed; allowed: "
                          f"{', '.join(map(repr, FORMATS))}, a COCO .json file or None")
    p = os.fspath(path)
    if os.path.isfile(p) and p.lower().endswith((".yaml", ".yml")):
        return _from_yaml(p, split, fmt, where)
    yml = next((os.path.join(p, n) for n in ("data.yaml", "data.yml")
                if os.path.isfile(os.path.join(p, n))), None)
    if yml and fmt in ("auto", "yolo") and _yaml_splits(read_yaml(yml, where)):
        return _from_yaml(yml, split, fmt, where)
    img_dir = _images_dir(p, split, where)
    ls = LabelSet(root=p, images=list_images(img_dir))
    if fmt is None:
        return ls
    if chosen is not None:
        ls.fmt, ls.coco_file = "coco", chosen
        return ls
    return _labels_of(ls, img_dir, fmt, split, where)


def _images_dir(root, split, where):
    sub = os.path.join(root, "images")
    if not os.path.isdir(sub):
        return root
    return _split_dir(sub, split, where)


def _split_dir(folder, split, where):
    if list_images(folder) and split is None:
        return folder
    subs = sorted(d for d in os.listdir(folder) if os.path.isdir(os.path.join(folder, d)))
    if split is not None:
        if split not in subs:
            raise ConfigError(f"{where}: split = {split!r} is not a folder of {folder!r}; "
                              f"allowed: {', '.join(map(repr, subs)) or 'none'}")
        return os.path.join(folder, split)
    if len(subs) == 1:
        return os.path.join(folder, subs[0])
    pick = next((s for s in SPLITS if s in subs), None)
    if pick is None:
        raise ConfigError(f"{where}: {folder!r} holds no images and the split folders "
                          f"{subs}; pass split=")
    return os.path.join(folder, pick)


def _labels_of(ls, img_dir, fmt, split, where) -> LabelSet:
    root = ls.root
    coco = coco_file(root, split, where) or (
        coco_file(os.path.join(root, "annotations"), split, where)
        if os.path.isdir(os.path.join(root, "annotations")) else None)
    yolo_dir = _yolo_dir(root, img_dir)
    vis_dir = os.path.join(root, "annotations")
    has_vis = img_dir != root and os.path.isdir(vis_dir) and any(
        f.endswith(".txt") for f in os.listdir(vis_dir))
    if fmt == "auto":
        fmt = "coco" if coco else "yolo" if _any_label(ls.images, yolo_dir) else (
            "visdrone" if has_vis else None)
        if fmt is None:
            return ls
    if fmt == "coco":
        if not coco:
            raise ConfigError(f"{where}: folder {root!r} has no annotations.json or "
                              f"instances*.json (in the folder or its annotations/)")
        ls.fmt, ls.coco_file = "coco", coco
        return ls
    label_dir = yolo_dir if fmt == "yolo" else vis_dir
    if fmt == "visdrone" and not os.path.isdir(vis_dir):
        raise ConfigError(f"{where}: a VisDrone-DET folder has images/ and annotations/; "
                          f"{root!r} has no annotations/")
    ls.fmt, ls.label_dir = fmt, label_dir
    ls.label_files = [_label_path(f, label_dir, where) for f in ls.images]
    if fmt == "yolo":
        ls.names = _declared_names(root, where)
    return ls


def _yolo_dir(root, img_dir):
    """Ultralytics' rule: the labels of .../images/x.jpg are in .../labels/x.txt."""
    if img_dir == root:
        return root
    rel = os.path.relpath(img_dir, os.path.join(root, "images"))
    return os.path.normpath(os.path.join(root, "labels", rel))


def _label_path(image, label_dir, where="annotations"):
    p = os.path.join(label_dir, os.path.splitext(os.path.basename(image))[0] + ".txt")
    return p if regular(p, where) else None


def _any_label(images, label_dir) -> bool:
    return os.path.isdir(label_dir) and any(
        os.path.lexists(os.path.join(label_dir, os.path.splitext(os.path.basename(f))[0] + ".txt"))
        for f in images)


def coco_file(folder, split=None, where="annotations"):
    """The COCO file of a folder: annotations.json or an instances*.json when it is the
    only one, else the one ``split`` names (``instances_<split>*.json``); several and
    no split to choose: ConfigError listing them."""
    if not os.path.isdir(folder):
        return None
    names = sorted(f for f in os.listdir(folder) if f == "annotations.json"
                   or f.startswith("instances") and f.endswith(".json"))
    found = [os.path.join(folder, n) for n in names if regular(os.path.join(folder, n), where)]
    if len(found) > 1 and split is not None:
        picked = [f for f in found if os.path.basename(f).startswith(f"instances_{split}")]
        if len(picked) == 1:
            return picked[0]
    if len(found) > 1:
        raise ConfigError(f"{where}: folder {folder!r} holds {len(found)} COCO files "
                          f"({', '.join(os.path.basename(f) for f in found)}); choose one: "
                          f"split='val' reads instances_val*.json, or annotations='<file>.json'"
                          f"{f' (split = {split!r} matches none or several)' if split else ''}")
    return found[0] if found else None


def _declared_names(root, where):
    txt = os.path.join(root, "classes.txt")
    if regular(txt, where):
        return tuple(line.strip() for line in read_text(txt, where).splitlines() if line.strip())
    for n in ("data.yaml", "data.yml"):
        y = os.path.join(root, n)
        if os.path.isfile(y):
            return yaml_names(read_yaml(y, where), y, where)
    return None


# -- Ultralytics data.yaml ----------------------------------------------------------
def _yaml_splits(doc) -> list:
    return [k for k in SPLITS if doc.get(k)]


def _from_yaml(path, split, fmt, where) -> LabelSet:
    if fmt not in ("auto", "yolo", None):
        raise ConfigError(f"{where}: {path!r} is an Ultralytics data.yaml (YOLO labels); "
                          f"annotations = {fmt!r} does not read it")
    doc = read_yaml(path, where)
    splits = _yaml_splits(doc)
    if split is None:
        if not splits:
            raise ConfigError(f"{where}: {path!r} has no 'val:', 'test:' or 'train:' image folder")
        split = splits[0]
    elif split not in splits:
        raise ConfigError(f"{where}: split = {split!r} is not in {path!r}; allowed: "
                          f"{', '.join(map(repr, splits)) or 'none'}")
    base = os.path.dirname(os.path.abspath(path))
    root = os.path.normpath(os.path.join(base, doc.get("path") or "."))
    img_dir = os.path.normpath(os.path.join(root, doc[split]))
    if not os.path.isdir(img_dir):
        raise ConfigError(f"{where}: {path!r} {split}: {doc[split]!r} is not a folder "
                          f"(looked in {img_dir!r})")
    ls = LabelSet(root=root, images=list_images(img_dir))
    if fmt is None:
        return ls
    head, sep, tail = img_dir.rpartition(os.sep + "images")
    label_dir = head + os.sep + "labels" + tail if sep else img_dir
    ls.fmt, ls.label_dir = "yolo", label_dir
    ls.label_files = [_label_path(f, label_dir, where) for f in ls.images]
    ls.names = yaml_names(doc, path, where)
    return ls


def read_yaml(path, where) -> dict:
    """The top-level keys of a data.yaml: scalars, inline lists/dicts, and blocks of
    ``- item`` / ``key: value`` lines (what Ultralytics' files use)."""
    doc: dict = {}
    key = None
    for line in read_text(path, where).splitlines(keepends=True):
        s = line.split(" #")[0].rstrip()
        if not s.strip() or s.lstrip().startswith("#"):
            continue
        if not line[:1].isspace() and ":" in s:
            key, _, rest = s.partition(":")
            key, rest = key.strip(), rest.strip()
            doc[key] = _inline(rest) if rest else []
        elif key is not None and line[:1].isspace():
            item = s.strip()
            if item.startswith("-"):
                _add(doc, key, None, _scalar(item[1:]))
            elif ":" in item:
                k, _, v = item.partition(":")
                _add(doc, key, _scalar(k), _scalar(v))
        else:
            raise ConfigError(f"{where}: {path!r}: line {line.rstrip()!r} is not 'key: value'")
    return doc


def _add(doc, key, k, v):
    cur = doc.get(key)
    if k is None:
        doc[key] = (cur if isinstance(cur, list) else []) + [v]
    else:
        doc[key] = {**(cur if isinstance(cur, dict) else {}), k: v}


def _inline(rest):
    if rest.startswith("[") and rest.endswith("]"):
        return [_scalar(x) for x in rest[1:-1].split(",") if x.strip()]
    if rest.startswith("{") and rest.endswith("}"):
        pairs = [x.split(":", 1) for x in rest[1:-1].split(",") if x.strip()]
        return {_scalar(k): _scalar(v) for k, v in pairs}
    return _scalar(rest)


def _scalar(s):
    s = s.strip().strip("'\"")
    return int(s) if s.lstrip("-").isdigit() else s


def yaml_names(doc, path, where) -> tuple:
    """The class names of a data.yaml's ``names:`` (a list, or a dict of index: name)."""
    names = doc.get("names")
    if isinstance(names, dict):
        keys = sorted(names)
        if keys != list(range(len(keys))):
            raise ConfigError(f"{where}: {path!r} names: indices {keys} are not 0..{len(keys) - 1}")
        names = [names[k] for k in keys]
    if not isinstance(names, list) or not names:
        raise ConfigError(f"{where}: {path!r} has no 'names:' list")
    return tuple(str(n) for n in names)
