"""A small ONNX network for the profiling tests: two 3x3 convolutions and a pooling,
with every attribute written out (``kernel_shape`` included: OpenCV's DNN importer
before 4.10 will not infer it), seeded weights, opset 17."""

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper


def conv_net(path, width=16, side=64, batch="n", seed=0):
    """Write the network to ``path`` and return it; ``batch`` the input's first dim
    (a name for a dynamic batch, or an int), ``side`` the input's height and width."""
    rng = np.random.default_rng(seed)
    w1 = numpy_helper.from_array(rng.standard_normal((width, 3, 3, 3)).astype(np.float32), "w1")
    w2 = numpy_helper.from_array(rng.standard_normal((width, width, 3, 3)).astype(np.float32),
                                 "w2")
    conv = {"kernel_shape": [3, 3], "pads": [1] * 4, "strides": [1, 1]}
    nodes = [helper.make_node("Conv", ["x", "w1"], ["c1"], **conv),
             helper.make_node("Relu", ["c1"], ["r1"]),
             helper.make_node("Conv", ["r1", "w2"], ["c2"], **conv),
             helper.make_node("GlobalAveragePool", ["c2"], ["y"])]
    g = helper.make_graph(nodes, "net", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [batch, 3, side, side])],
        [helper.make_tensor_value_info("y", TensorProto.FLOAT, [batch, width, 1, 1])], [w1, w2])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, str(path))
    return path
