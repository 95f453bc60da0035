"""Writes tiny.ncnn.param and tiny.ncnn.bin beside this file: the ncnn model
tests/compute/test_compute_profile.py times with ncnn's Python binding (the suite does not
need pnnx). It is tests/onnx_nets.conv_net(width 8, 64x64, batch 1) converted by pnnx,
the converter ncnn's maintainers ship (``pip install pnnx``; pnnx 20261020 wrote these),
less pnnx's trailing Reshape back to [1, 8, 1, 1] (an expression parameter that ncnn
releases before 2025 cannot parse; ncnn's blobs have no batch dim anyway), so that the
lowest ncnn the package supports loads it too.

    python -m venv /tmp/pnnx && /tmp/pnnx/bin/pip install pnnx onnx numpy
    /tmp/pnnx/bin/python tests/compute/data/make_ncnn.py
"""

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from onnx_nets import conv_net  # noqa: E402


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        onnx_path = conv_net(Path(tmp) / "tiny.onnx", 8, side=64, batch=1)
        subprocess.run([shutil.which("pnnx") or "pnnx", str(onnx_path)], cwd=tmp, check=True)
        shutil.copy(Path(tmp) / "tiny.ncnn.bin", HERE / "tiny.ncnn.bin")
        (HERE / "tiny.ncnn.param").write_text(without_last_reshape(
            (Path(tmp) / "tiny.ncnn.param").read_text()))


def without_last_reshape(param: str) -> str:
    """The .param text without its last layer when that is a Reshape: the layer before it
    writes the Reshape's output blob instead, and the layer and blob counts drop by one.
    A layer line: type, name, n_in, n_out, the inputs, the outputs, then k=v parameters."""
    magic, counts, *layers = param.strip().splitlines()
    last = layers[-1].split()
    if last[0] != "Reshape":
        return param
    blob_in, blob_out = last[4], last[5]
    kept = []
    for line in layers[:-1]:
        t = line.split()
        n_in, n_out = int(t[2]), int(t[3])
        outs = [blob_out if b == blob_in else b for b in t[4 + n_in:4 + n_in + n_out]]
        kept.append(" ".join(t[:4 + n_in] + outs + t[4 + n_in + n_out:]))
    n_layers, n_blobs = (int(c) for c in counts.split())
    return "\n".join([magic, f"{n_layers - 1} {n_blobs - 1}", *kept]) + "\n"


if __name__ == "__main__":
    main()
