"""Reference network summaries: per-node costs of the networks in the published table.

Two steps, two interpreters (torch is a dev-time tool, not a dependency):

1. ``export`` (a venv with torch, torchvision, timm, ultralytics, onnx):
   builds each architecture with random weights (no download) and writes it with plain
   ``torch.onnx.export`` (TorchScript exporter, ``dynamo=False``, opset 17, default
   constant folding, not simplified) to ``DIR/<network>-<input>.onnx``, plus
   ``DIR/index.json`` (builder, exporter, versions). ONNX files stay out of the repo.
2. ``summarize`` (the project's venv): ``pytest_flockai.compute.graph.analyze`` on each
   file, writing ``pytest_flockai/compute/data/networks/<network>-<input>.csv`` (nodes
   folded into constants dropped, nodes named by their index in the exported graph;
   header lines say what produced it) and ``networks/index.csv`` (one row a network).

    /work/torchvenv/bin/python benchmarks/export_networks.py export /tmp/nets [--only ID ...]
    python benchmarks/export_networks.py summarize /tmp/nets

Which (network, input) pairs: ``NETWORKS`` below at their usual input, plus every
(network, input) of ``compute/data/published_latency.csv`` when that file is present.
Architectures not in torchvision / timm / ultralytics are small modules here:
``ssd_mobilenet_v1`` and ``ssd_mobilenet_v2`` follow the TensorFlow Object Detection
API's SSD configs (Liu et al. 2016; Huang et al. 2017, "Speed/accuracy trade-offs for
modern convolutional object detectors"): feature maps at stride 16 and 32, four extra
1x1-then-3x3/2 layers (512, 256, 256, 128), 1x1 box and class predictors with 3 anchors
on the first map and 6 on the rest, 91 classes. Detection models are exported up to
their raw head outputs (no NMS): the runtimes' tables time the same.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "pytest_flockai" / "compute" / "data"
OUT = DATA / "networks"
OPSET = 17

#: network id -> (usual square input, builder description)
NETWORKS = {
    **{n: (640, f"ultralytics YOLO('{n}.yaml') DetectionModel") for n in (
        "yolov8n", "yolov8s", "yolov8m", "yolov8l", "yolo11n", "yolo11s", "yolo11m", "yolo11l",
        "yolov5nu", "yolov5su", "yolo26n", "yolo26s", "yolo26m", "yolo26l",
        "yolov9t", "yolov9s", "yolov9m", "yolov10n", "yolov10s", "yolov10m")},
    **{n: (224, f"torchvision.models.{n}(weights=None)") for n in (
        "resnet18", "resnet50", "resnet101", "mobilenet_v2", "mobilenet_v3_small",
        "mobilenet_v3_large", "efficientnet_b0", "squeezenet1_1", "vgg16", "densenet121",
        "googlenet", "alexnet")},
    "shufflenet_v2": (224, "torchvision.models.shufflenet_v2_x1_0(weights=None)"),
    "inception_v3": (299, "torchvision.models.inception_v3(weights=None, aux_logits=False)"),
    "mobilenet_v1": (224, "timm mobilenetv1_100 (Howard et al. 2017, width 1.0)"),
    "efficientnet_lite0": (224, "timm efficientnet_lite0"),
    "inception_v4": (299, "timm inception_v4"),
    "ssd_mobilenet_v1": (300, "SSD on MobileNetV1 (this script), TF OD API layout, to heads"),
    "ssd_mobilenet_v2": (300, "SSD on MobileNetV2 (this script), TF OD API layout, to heads"),
    "ssdlite_mobilenet_v3": (320, "torchvision ssdlite320_mobilenet_v3_large(weights=None, "
                                  "weights_backbone=None), backbone + head"),
}


def pairs(table: Path | None = None) -> list[tuple[str, int]]:
    """(network, input) pairs: the usual inputs plus the published table's."""
    want = {(n, s) for n, (s, _) in NETWORKS.items()}
    table = table or DATA / "published_latency.csv"
    if table.is_file():
        with open(table, encoding="utf-8") as fh:
            for row in csv.DictReader(r for r in fh if not r.startswith("#")):
                if row.get("network") in NETWORKS and str(row.get("input", "")).isdigit():
                    want.add((row["network"], int(row["input"])))
    return sorted(want)


# -- step 1: export (torch venv) -------------------------------------------------------
def _ssd(backbone_taps, channels, nn, torch):
    """SSD extras and 1x1 predictors on two backbone maps (TF OD API layout)."""
    class SSD(nn.Module):
        def __init__(self):
            super().__init__()
            self.taps = backbone_taps
            extras, c = [], channels[1]
            for mid, out in ((256, 512), (128, 256), (128, 256), (64, 128)):
                extras.append(nn.Sequential(
                    nn.Conv2d(c, mid, 1, bias=False), nn.BatchNorm2d(mid), nn.ReLU6(),
                    nn.Conv2d(mid, out, 3, 2, 1, bias=False), nn.BatchNorm2d(out), nn.ReLU6()))
                c = out
            self.extras = nn.ModuleList(extras)
            chans = [channels[0], channels[1], 512, 256, 256, 128]
            anchors = [3, 6, 6, 6, 6, 6]
            self.box = nn.ModuleList(nn.Conv2d(ch, a * 4, 1) for ch, a in zip(chans, anchors))
            self.cls = nn.ModuleList(nn.Conv2d(ch, a * 91, 1) for ch, a in zip(chans, anchors))

        def forward(self, x):
            maps = list(self.taps(x))
            for e in self.extras:
                maps.append(e(maps[-1]))
            boxes = [b(m).permute(0, 2, 3, 1).reshape(1, -1, 4) for b, m in zip(self.box, maps)]
            scores = [c(m).permute(0, 2, 3, 1).reshape(1, -1, 91)
                      for c, m in zip(self.cls, maps)]
            return torch.cat(boxes, 1), torch.cat(scores, 1)
    return SSD()


def _build(name: str):
    import timm
    import torch
    import torchvision
    from torch import nn
    tv = torchvision.models
    if name.startswith("yolo"):
        from ultralytics import YOLO
        m = YOLO(f"{name}.yaml").model
        for mod in m.modules():          # what ultralytics' own ONNX export sets
            if hasattr(mod, "export"):
                mod.export = True
            if hasattr(mod, "format"):
                mod.format = "onnx"
        return m
    if name == "shufflenet_v2":
        return tv.shufflenet_v2_x1_0(weights=None)
    if name == "inception_v3":
        return tv.inception_v3(weights=None, aux_logits=False, init_weights=False)
    if name == "googlenet":
        return tv.googlenet(weights=None, aux_logits=False, init_weights=False)
    if name in ("mobilenet_v1", "efficientnet_lite0", "inception_v4"):
        return timm.create_model({"mobilenet_v1": "mobilenetv1_100"}.get(name, name),
                                 pretrained=False)
    if name == "ssdlite_mobilenet_v3":
        det = tv.detection.ssdlite320_mobilenet_v3_large(weights=None, weights_backbone=None)

        class Heads(nn.Module):
            def __init__(self):
                super().__init__()
                self.backbone, self.head = det.backbone, det.head

            def forward(self, x):
                out = self.head(list(self.backbone(x).values()))
                return out["bbox_regression"], out["cls_logits"]
        return Heads()
    if name == "ssd_mobilenet_v1":
        body = timm.create_model("mobilenetv1_100", pretrained=False, features_only=True,
                                 out_indices=(3, 4))
        return _ssd(body, body.feature_info.channels(), nn, torch)
    if name == "ssd_mobilenet_v2":
        f = tv.mobilenet_v2(weights=None).features

        class Taps(nn.Module):       # 576-ch expansion of block 14 (stride 16), last conv
            def __init__(self):
                super().__init__()
                self.head, self.expand = f[:14], f[14].conv[0]
                self.rest, self.tail = f[14].conv[1:], f[15:]

            def forward(self, x):
                x = self.head(x)
                e = self.expand(x)
                return e, self.tail(self.rest(e))
        return _ssd(Taps(), (576, 1280), nn, torch)
    return getattr(tv, name)(weights=None)


def export(out_dir: Path, only: list[str], table: Path | None = None) -> None:
    import warnings

    import onnx
    import torch
    import torchvision
    warnings.filterwarnings("ignore")
    out_dir.mkdir(parents=True, exist_ok=True)
    index_path = out_dir / "index.json"
    index = json.loads(index_path.read_text()) if index_path.is_file() else {}
    versions = {"torch": torch.__version__, "torchvision": torchvision.__version__,
                "onnx": onnx.__version__}
    for mod in ("timm", "ultralytics"):
        versions[mod] = __import__(mod).__version__
    torch.manual_seed(0)
    for name, side in pairs(table):
        if only and name not in only:
            continue
        stem = f"{name}-{side}"
        path = out_dir / f"{stem}.onnx"
        if path.is_file() and stem in index:
            continue
        model = _build(name).eval()
        x = torch.zeros(1, 3, side, side)
        with torch.no_grad():
            torch.onnx.export(model, (x,), str(path), opset_version=OPSET, dynamo=False,
                              input_names=["images"])
        index[stem] = {"network": name, "input": side, "builder": NETWORKS[name][1],
                       "exporter": f"torch.onnx.export (TorchScript, dynamo=False) torch "
                                   f"{versions['torch']}", "opset": OPSET,
                       "simplified": "no", "weights": "random (architecture only)",
                       "versions": versions}
        index_path.write_text(json.dumps(index, indent=1, sort_keys=True))
        print(f"exported {stem}: {path.stat().st_size / 2**20:.1f} MiB", flush=True)


# -- step 2: summarize (project venv) -----------------------------------------------------
def summarize(in_dir: Path) -> None:
    from dataclasses import replace

    sys.path.insert(0, str(ROOT))
    from pytest_flockai.compute.graph import FOLDED, NetworkCost, analyze
    index = json.loads((in_dir / "index.json").read_text())
    rows = []
    for stem in sorted(index):
        info = index[stem]
        path = in_dir / f"{stem}.onnx"
        if not path.is_file():
            continue
        cost = analyze(path, name=stem)
        ids = {n.name: str(i) for i, n in enumerate(cost.nodes)}
        kept = tuple(replace(n, name=ids[n.name],
                             fused_into=None if n.fused_into is None else ids[n.fused_into])
                     for n in cost.nodes if n.fused_into != FOLDED)
        meta = {"network": info["network"], "input": info["input"],
                "builder": info["builder"], "exporter": info["exporter"],
                "opset": info["opset"], "simplified": info["simplified"],
                "weights": info["weights"], "shapes": cost.meta["shapes"],
                "nodes": (f"{len(kept)} of {len(cost.nodes)} exported nodes (constant-folded "
                          f"ones dropped), named by their index in the exported graph")}
        small = NetworkCost(kept, stem, cost.input_shape, cost.uncounted, meta)
        small.to_csv(OUT / f"{stem}.csv")
        rows.append({"network": info["network"], "input": info["input"], "file": f"{stem}.csv",
                     "macs": small.macs, "weight_elems": small.weight_elems,
                     "nodes": len(kept), "run_nodes": len(small.run_nodes),
                     "opset": info["opset"], "exporter": info["exporter"],
                     "builder": info["builder"]})
        print(f"{stem:28s} {small.macs / 1e9:8.3f} GMAC {small.weight_elems / 1e6:7.2f} M "
              f"weights {len(small.run_nodes):4d} run nodes ({cost.meta['shapes']})", flush=True)
    with open(OUT / "index.csv", "w", encoding="utf-8", newline="") as fh:
        w = csv.DictWriter(fh, list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export", help="export ONNX files (needs torch)")
    e.add_argument("dir", type=Path)
    e.add_argument("--only", nargs="*", default=[])
    e.add_argument("--table", type=Path, default=None,
                   help="published_latency.csv to read pairs from (default: the package's)")
    s = sub.add_parser("summarize", help="write the per-node CSVs (project venv)")
    s.add_argument("dir", type=Path)
    a = ap.parse_args(argv)
    os.environ.setdefault("YOLO_OFFLINE", "1")
    if a.cmd == "export":
        export(a.dir, a.only, a.table)
    else:
        summarize(a.dir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
