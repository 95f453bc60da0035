"""compute.graph: per-node costs, classes, fusion and shapes through the whole graph."""

import csv
import re
from importlib import resources

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper

from pytest_flockai.compute.graph import FOLDED, NetworkCost, analyze
from pytest_flockai.errors import ConfigError
from pytest_flockai.ml import count_macs

_RNG = np.random.default_rng(3)


def _w(name, shape):
    return numpy_helper.from_array(_RNG.standard_normal(shape).astype(np.float32), name)


def _i64(name, values):
    return numpy_helper.from_array(np.asarray(values, np.int64), name)


def _model(nodes, inputs, outputs, inits, opset=17):
    g = helper.make_graph(nodes, "g", inputs, outputs, inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", opset)])
    m.ir_version = 8
    return m


def _x(shape):
    return helper.make_tensor_value_info("x", TensorProto.FLOAT, shape)


def _y(name="y"):
    return helper.make_tensor_value_info(name, TensorProto.FLOAT, None)


def _silu(src, dst, tag):
    return [helper.make_node("Sigmoid", [src], [f"{tag}_s"], name=f"{tag}/Sigmoid"),
            helper.make_node("Mul", [src, f"{tag}_s"], [dst], name=f"{tag}/Mul")]


def _conv(src, dst, w, tag, **kw):
    return helper.make_node("Conv", [src, w], [dst], name=f"{tag}/Conv", **kw)


def test_classes_fusion_folding_and_csv_round_trip(tmp_path):
    nodes = [
        _conv("x", "c1", "w1", "a", pads=[1, 1, 1, 1]),                       # 1x8x8x8 dense
        helper.make_node("BatchNormalization", ["c1", "g", "b", "m", "v"], ["n1"], name="a/BN"),
        helper.make_node("Relu", ["n1"], ["r1"], name="a/Relu"),
        _conv("r1", "d1", "wd", "dw", pads=[1, 1, 1, 1], group=8),            # depthwise
        *_silu("d1", "s1", "dw"),
        helper.make_node("Shape", ["s1"], ["sh"], name="shape/Shape"),       # folded: static
        helper.make_node("Gather", ["sh", "zero"], ["n0"], name="shape/Gather", axis=0),
        helper.make_node("Unsqueeze", ["n0", "zero1"], ["n0u"], name="shape/Unsqueeze"),
        helper.make_node("Concat", ["n0u", "minus1"], ["flat"], name="shape/Concat", axis=0),
        helper.make_node("Reshape", ["s1", "flat"], ["f"], name="head/Reshape"),  # 1x512
        helper.make_node("MatMul", ["f", "wm"], ["mm"], name="head/MatMul"),       # 1x10
        helper.make_node("Add", ["mm", "bm"], ["ab"], name="head/Add"),
        helper.make_node("Relu", ["ab"], ["y"], name="head/Relu"),
    ]
    inits = [_w("w1", (8, 3, 3, 3)), _w("g", (8,)), _w("b", (8,)), _w("m", (8,)),
             numpy_helper.from_array(np.ones(8, np.float32), "v"), _w("wd", (8, 1, 3, 3)),
             _i64("zero", 0), _i64("zero1", [0]), _i64("minus1", [-1]), _w("wm", (512, 10)),
             _w("bm", (10,))]
    cost = analyze(_model(nodes, [_x([1, 3, 8, 8])], [_y()], inits), name="small")
    by = {n.name: n for n in cost.nodes}
    assert by["a/Conv"].kind == "conv" and by["a/Conv"].macs == 512 * 27
    assert by["a/Conv"].weight_elems == 8 * 27 and by["a/Conv"].in_elems == 192
    assert by["dw/Conv"].kind == "dwconv" and by["dw/Conv"].macs == 512 * 9
    assert by["head/MatMul"].kind == "matmul" and by["head/MatMul"].macs == 10 * 512
    assert by["head/Reshape"].kind == "data" and by["head/Reshape"].macs == 0
    assert {n: by[n].fused_into for n in ("a/BN", "a/Relu")} == {"a/BN": "a/Conv",
                                                                 "a/Relu": "a/Conv"}
    assert by["dw/Sigmoid"].fused_into == by["dw/Mul"].fused_into == "dw/Conv"
    assert by["head/Add"].fused_into == by["head/Relu"].fused_into == "head/MatMul"
    assert all(by[f"shape/{k}"].fused_into == FOLDED for k in ("Shape", "Gather", "Unsqueeze",
                                                               "Concat"))
    assert [n.name for n in cost.run_nodes] == ["a/Conv", "dw/Conv", "head/Reshape",
                                                "head/MatMul"]
    kinds = cost.by_kind()
    assert kinds["conv"] == 512 * 27 and kinds["dwconv"] == 512 * 9
    assert cost.macs == sum(kinds.values()) == count_macs(
        _model(nodes, [_x([1, 3, 8, 8])], [_y()], inits)).macs
    assert cost.input_shape == (1, 3, 8, 8) and cost.uncounted == ()
    back = NetworkCost.from_csv(cost.to_csv(tmp_path / "small.csv"))
    assert back == cost and NetworkCost.from_csv((tmp_path / "small.csv").read_text()) == cost
    bad = cost.to_csv().replace(",dwconv,", ",warp,")
    with pytest.raises(ConfigError, match=r"row \d+ .*kind in"):
        NetworkCost.from_csv(bad)
    with pytest.raises(ConfigError, match="schema"):
        NetworkCost.from_csv("name,op_type\nx,y\n")


def _yolo_like():
    """A YOLOv8n-style block as plain torch.onnx.export writes it: SiLU as Sigmoid*Mul,
    C2f's chunk as a Split whose sizes are computed from the tensor's shape, a
    bottleneck with a residual Add, an upsample whose Resize sizes are computed, a
    concat with the stem, and a head reshaped with Shape/Gather/Concat arithmetic."""
    n = [_conv("x", "c1", "w1", "m0", pads=[1] * 4, strides=[2, 2]), *_silu("c1", "s1", "m0"),
         _conv("s1", "c2", "w2", "m1", pads=[1] * 4, strides=[2, 2]), *_silu("c2", "s2", "m1"),
         _conv("s2", "c3", "w3", "m2.cv1"), *_silu("c3", "s3", "m2.cv1"),
         helper.make_node("Shape", ["s3"], ["sh3"], name="m2/Shape"),
         helper.make_node("Gather", ["sh3", "one"], ["ch"], name="m2/Gather", axis=0),
         helper.make_node("Div", ["ch", "two"], ["half"], name="m2/Div"),
         helper.make_node("Unsqueeze", ["half", "zero1"], ["half1"], name="m2/Unsqueeze"),
         helper.make_node("Concat", ["half1", "half1"], ["sizes"], name="m2/Concat", axis=0),
         helper.make_node("Split", ["s3", "sizes"], ["a", "b"], name="m2/Split", axis=1),
         _conv("b", "c4", "w4", "m2.m.0", pads=[1] * 4), *_silu("c4", "s4", "m2.m.0"),
         helper.make_node("Add", ["b", "s4"], ["r4"], name="m2.m.0/Add"),
         helper.make_node("Concat", ["a", "b", "r4"], ["cat"], name="m2/Concat_1", axis=1),
         _conv("cat", "c5", "w5", "m2.cv2"), *_silu("c5", "s5", "m2.cv2"),
         helper.make_node("Shape", ["s5"], ["sh5"], name="up/Shape"),
         helper.make_node("Slice", ["sh5", "zero1", "two1"], ["nc"], name="up/Slice"),
         helper.make_node("Slice", ["sh5", "two1", "four1"], ["hw"], name="up/Slice_1"),
         helper.make_node("Mul", ["hw", "two"], ["hw2"], name="up/Mul"),
         helper.make_node("Concat", ["nc", "hw2"], ["size"], name="up/Concat", axis=0),
         helper.make_node("Resize", ["s5", "", "", "size"], ["up"], name="up/Resize",
                          mode="nearest"),
         helper.make_node("Concat", ["up", "s1"], ["cat2"], name="m4/Concat", axis=1),
         _conv("cat2", "c6", "w6", "m5"), *_silu("c6", "s6", "m5"),
         helper.make_node("Shape", ["s6"], ["sh6"], name="head/Shape"),
         helper.make_node("Gather", ["sh6", "zero"], ["bs"], name="head/Gather", axis=0),
         helper.make_node("Unsqueeze", ["bs", "zero1"], ["bs1"], name="head/Unsqueeze"),
         helper.make_node("Concat", ["bs1", "c16", "minus1"], ["rs"], name="head/Concat", axis=0),
         helper.make_node("Reshape", ["s6", "rs"], ["flat"], name="head/Reshape"),
         helper.make_node("Transpose", ["flat"], ["t"], name="head/Transpose", perm=[0, 2, 1]),
         helper.make_node("MatMul", ["t", "wm"], ["mm"], name="head/MatMul"),
         helper.make_node("Sigmoid", ["mm"], ["y"], name="head/Sigmoid")]
    inits = [_w("w1", (16, 3, 3, 3)), _w("w2", (32, 16, 3, 3)), _w("w3", (32, 32, 1, 1)),
             _w("w4", (16, 16, 3, 3)), _w("w5", (32, 48, 1, 1)), _w("w6", (16, 48, 1, 1)),
             _w("wm", (16, 4)), _i64("zero", 0), _i64("one", 1), _i64("two", 2),
             _i64("zero1", [0]), _i64("two1", [2]), _i64("four1", [4]), _i64("c16", [16]),
             _i64("minus1", [-1])]
    return _model(n, [_x(["batch", 3, "h", "w"])], [_y()], inits)


def _yolo_like_hand_count(s=64):
    e1, e2 = 16 * (s // 2) ** 2, 32 * (s // 4) ** 2        # stem (stride 2), stride 4 maps
    half = e2 // 2
    convs = (e1 * 27 + e2 * 16 * 9 + e2 * 32                # m0, m1, m2.cv1
             + half * 16 * 9 + e2 * 48                      # bottleneck, m2.cv2
             + e1 * 48)                                     # m5 after the upsample concat
    silu = 2 * (e1 + e2 + e2 + half + e2 + e1)              # Sigmoid + Mul per SiLU
    add, resize = half, 2 * e1                              # residual; 32 ch at stride 2
    head = (s // 2) ** 2 * 4 * 16 + (s // 2) ** 2 * 4       # MatMul M N K, Sigmoid
    return convs + silu + add + resize + head


def test_yolo_like_torch_export_counts_whole_graph(tmp_path):
    m = _yolo_like()
    path = tmp_path / "yolo_like.onnx"
    onnx.save(m, str(path))
    hand = _yolo_like_hand_count(64)
    cost = analyze(path, 64)
    assert cost.uncounted == () and cost.input_shape == (1, 3, 64, 64)
    assert abs(cost.macs - hand) <= 0.02 * hand
    assert cost.macs == hand                       # exact: every node has its shapes
    assert cost.meta["shapes"] == "onnx+onnxruntime"   # the computed Split needed the run
    by = {n.name: n for n in cost.nodes}
    assert by["m2.m.0/Conv"].macs == 16 * 16 * 16 * 16 * 9      # after the computed Split
    assert by["m5/Conv"].macs == 16 * 32 * 32 * 48               # after the computed Resize
    assert by["up/Resize"].out_elems == 32 * 32 * 32
    assert by["m2/Div"].fused_into == FOLDED and by["up/Mul"].fused_into == FOLDED
    assert count_macs(path, {"x": [1, 3, 64, 64]}).macs == hand
    # another size: the Split and Resize follow it
    assert analyze(m, (1, 3, 96, 96)).macs == _yolo_like_hand_count(96)


def test_dynamic_input_without_shape_and_bad_inputs_are_refused(tmp_path):
    with pytest.raises(ConfigError, match=r"input 'x' .* has dims \[1, 3, 'h', 'w'\]"):  # its names
        analyze(_yolo_like())
    with pytest.raises(ConfigError, match="model = 3.5 is not allowed"):
        analyze(3.5)
    with pytest.raises(ConfigError, match="not a valid ONNX model"):
        analyze(b"not onnx")
    with pytest.raises(ConfigError, match="'nope' is not an input"):
        analyze(_yolo_like(), {"nope": (1, 3, 8, 8)})
    with pytest.raises(ConfigError, match="does not exist"):
        analyze(tmp_path / "missing.onnx")


def test_unreadable_shapes_are_refused_naming_the_nodes_or_warned():
    # a custom op ONNX Runtime cannot run: the nodes after it have no shape from any engine
    nodes = [helper.make_node("Warp", ["x"], ["w"], name="pre/warp", domain="com.example"),
             _conv("w", "c", "wc", "body"), helper.make_node("Relu", ["c"], ["y"], name="act")]
    m = _model(nodes, [_x([1, 3, 8, 8])], [_y()], [_w("wc", (4, 3, 3, 3))])
    m.opset_import.append(helper.make_opsetid("com.example", 1))
    with pytest.raises(ConfigError, match=r"3 of 3 nodes .*Warp pre/warp: custom domain.*"
                                          r"Conv body/Conv: shapes unknown"):
        analyze(m)
    with pytest.warns(UserWarning, match=r"\(100.0%\) are not counted"):
        cost = analyze(m, allow_uncounted=True)
    assert cost.macs == 0 and len(cost.uncounted) == 3


def test_reference_network_summaries_load_and_agree_with_their_index():
    nets = resources.files("pytest_flockai.compute") / "data" / "networks"
    with (nets / "index.csv").open(encoding="utf-8") as fh:
        index = list(csv.DictReader(fh))
    assert len(index) >= 29
    for row in index:
        cost = NetworkCost.from_csv(str(nets / row["file"]))
        assert cost.macs == int(row["macs"]) and len(cost.run_nodes) == int(row["run_nodes"])
        assert cost.meta["opset"] == "17" and cost.uncounted == ()
        names = {n.name for n in cost.nodes}
        assert all(n.fused_into in names for n in cost.nodes if n.fused_into is not None)
        assert cost.input_shape == (1, 3, int(row["input"]), int(row["input"]))
    macs = {r["file"]: int(r["macs"]) for r in index}
    assert abs(macs["yolov8n-640.csv"] / 4.41e9 - 1) < 0.02      # plain torch.onnx.export
    assert abs(macs["resnet50-224.csv"] / 4.1e9 - 1) < 0.02      # He et al. 2016: 4.1 GMAC
    assert abs(macs["mobilenet_v2-224.csv"] / 300e6 - 1) < 0.03  # Sandler et al. 2018: 300 M


def _ones(name, shape):
    return numpy_helper.from_array(np.full(shape, 0.01, np.float32), name)


def test_recurrent_einsum_and_attention_layers_are_counted():
    seq, batch, inp, hid = 7, 2, 12, 20
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [seq, batch, inp])
    for op, gates in (("LSTM", 4), ("GRU", 3), ("RNN", 1)):
        for dirs in (1, 2):
            node = helper.make_node(op, ["x", "W", "R"], ["y", "h"], name=op, hidden_size=hid,
                                    direction="bidirectional" if dirs == 2 else "forward")
            m = _model([node], [x], [_y()], [_ones("W", (dirs, gates * hid, inp)),
                                             _ones("R", (dirs, gates * hid, hid))])
            cost = analyze(m)
            assert cost.uncounted == () and cost.nodes[0].kind == "matmul"
            # every step: W x_t and R h_{t-1} per direction and gate
            assert cost.macs == seq * batch * dirs * gates * hid * (inp + hid), (op, dirs)
    # batch-first layout (opset 14): X is [batch, seq, input]
    node = helper.make_node("LSTM", ["x", "W", "R"], ["y"], name="lstm", hidden_size=hid, layout=1)
    bf = helper.make_tensor_value_info("x", TensorProto.FLOAT, [batch, seq, inp])
    m = _model([node], [bf], [_y()], [_ones("W", (1, 4 * hid, inp)), _ones("R", (1, 4 * hid, hid))])
    assert analyze(m).macs == seq * batch * 4 * hid * (inp + hid)
    # Einsum: output elements times the summed labels (a batched matmul, then a trace-like sum)
    a = helper.make_tensor_value_info("x", TensorProto.FLOAT, [3, 5, 6])
    node = helper.make_node("Einsum", ["x", "b"], ["y"], name="bmm", equation="bij,bjk->bik")
    m = _model([node], [a], [_y()], [_ones("b", (3, 6, 4))], opset=17)
    assert analyze(m).macs == 3 * 5 * 4 * 6
    node = helper.make_node("Einsum", ["x", "b"], ["y"], name="ell", equation="...ij,...jk")
    m = _model([node], [a], [_y()], [_ones("b", (3, 6, 4))], opset=17)
    assert analyze(m).macs == 3 * 5 * 4 * 6                      # implicit output ...ik
    node = helper.make_node("Einsum", ["x"], ["y"], name="sum", equation="bij->b")
    assert analyze(_model([node], [a], [_y()], [])).macs == 3 * 5 * 6


def test_attention_of_opset_23_is_counted():
    if onnx.defs.onnx_opset_version() < 23:
        pytest.skip(f"onnx {onnx.__version__} has no opset 23 (Attention)")
    b, h, sq, skv, d = 1, 4, 10, 16, 8
    q = helper.make_tensor_value_info("x", TensorProto.FLOAT, [b, h, sq, d])
    node = helper.make_node("Attention", ["x", "k", "v"], ["y"], name="attn")
    m = _model([node], [q], [_y()], [_ones("k", (b, h, skv, d)), _ones("v", (b, h, skv, d))],
               opset=23)
    m.ir_version = 10
    cost = analyze(m)
    # softmax(Q K^T) V: sq*skv*d for the scores and sq*skv*d for the weighted sum, per head
    assert cost.uncounted == () and cost.macs == 2 * b * h * sq * skv * d


def test_onnxruntime_contrib_operators_are_counted_as_what_they_stand_for():
    # ONNX Runtime's graph optimizer writes FusedConv (com.microsoft) for Conv + activation
    node = helper.make_node("FusedConv", ["x", "w"], ["y"], name="fc", domain="com.microsoft",
                            activation="Relu", pads=[1, 1, 1, 1], kernel_shape=[3, 3])
    m = _model([node], [_x([1, 3, 8, 8])], [_y()], [_w("w", (4, 3, 3, 3))])
    m.opset_import.append(helper.make_opsetid("com.microsoft", 1))
    cost = analyze(m)
    assert cost.uncounted == () and cost.nodes[0].kind == "conv"
    assert cost.macs == 4 * 8 * 8 * 3 * 9


def test_every_standard_operator_is_counted_or_left_out_by_name():
    """Each operator of the installed onnx's default domain has a rule (a class and MACs) or
    is in ``NOT_COUNTED`` (refused by name): none falls through unnoticed."""
    from pytest_flockai.compute import _ops
    ruled = (_ops.ELEMENTWISE | _ops.REDUCE | _ops.POOL | _ops.GLOBAL_POOL | _ops.RESAMPLE
             | _ops.CONV | _ops.MATMUL | _ops.ZERO | _ops.RECURRENT | {"Einsum", "Attention"})
    ops = {s.name for s in onnx.defs.get_all_schemas() if s.domain == ""}
    assert not (ruled & _ops.NOT_COUNTED)
    assert sorted(ops - ruled - _ops.NOT_COUNTED) == []


def test_a_transformer_block_as_the_legacy_exporter_writes_it_is_counted():
    seq, d, ff = 10, 16, 32
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, seq, d])
    nodes = [
        helper.make_node("LayerNormalization", ["x", "g", "b"], ["ln"], name="ln", axis=-1),
        helper.make_node("MatMul", ["ln", "wq"], ["q"], name="q"),
        helper.make_node("MatMul", ["ln", "wk"], ["k"], name="k"),
        helper.make_node("Transpose", ["k"], ["kt"], name="kt", perm=[0, 2, 1]),
        helper.make_node("MatMul", ["q", "kt"], ["s"], name="scores"),
        helper.make_node("Softmax", ["s"], ["p"], name="softmax", axis=-1),
        helper.make_node("MatMul", ["p", "ln"], ["a"], name="mix"),
        helper.make_node("MatMul", ["a", "w1"], ["h"], name="ff1"),
        helper.make_node("Div", ["h", "sqrt2"], ["hd"], name="gelu/div"),
        helper.make_node("Erf", ["hd"], ["he"], name="gelu/erf"),
        helper.make_node("MatMul", ["he", "w2"], ["o"], name="ff2"),
        helper.make_node("CumSum", ["o", "axis"], ["y"], name="cumsum"),
    ]
    inits = [_ones("g", (d,)), _ones("b", (d,)), _ones("wq", (d, d)), _ones("wk", (d, d)),
             _ones("w1", (d, ff)), _ones("w2", (ff, d)), _ones("sqrt2", ()),
             numpy_helper.from_array(np.asarray(1, np.int64), "axis")]
    cost = analyze(_model(nodes, [x], [_y()], inits))
    by = {n.name: n for n in cost.nodes}
    assert cost.uncounted == ()
    assert by["q"].macs == by["k"].macs == seq * d * d and by["q"].kind == "matmul"
    assert by["scores"].macs == seq * seq * d and by["mix"].macs == seq * d * seq
    assert by["ff1"].macs == seq * d * ff and by["ff2"].macs == seq * ff * d
    assert by["softmax"].macs == seq * seq and by["cumsum"].macs == seq * d
    assert by["ln"].kind == by["gelu/erf"].kind == "elementwise"


def test_a_model_that_does_not_run_says_so_first(tmp_path):
    """Shapes unknown because ONNX Runtime cannot run the model (here a Conv fed fp16 with
    fp32 weights, as a broken fp16 conversion writes): the error leads with that cause."""
    w = numpy_helper.from_array(np.ones((4, 3, 3, 3), np.float32), "w")
    g = helper.make_graph([helper.make_node("Cast", ["x"], ["h"], to=TensorProto.FLOAT16),
                           helper.make_node("Conv", ["h", "w"], ["y"], kernel_shape=[3, 3])],
                          "bad", [helper.make_tensor_value_info("x", TensorProto.FLOAT,
                                                                [1, 3, 8, 8])],
                          [helper.make_tensor_value_info("y", TensorProto.FLOAT, None)], [w])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, str(tmp_path / "bad.onnx"))
    with pytest.raises(ConfigError, match=r"^'bad' does not run in ONNX Runtime, so the shapes "
                                          r"of 1 of its 2 nodes are unknown \(.*onnxruntime "
                                          r"run for shapes failed: .*Conv"):
        analyze(tmp_path / "bad.onnx")


def test_the_reason_onnx_runtime_gives_survives_a_long_node_name(tmp_path):
    """HardSwish (opset 14) in an opset-13 graph, named as tf2onnx names nodes (hundreds of
    characters): ONNX Runtime's reason, which comes after the name, is in the error."""
    name = ";".join(f"MobilenetV3small/block_{i}/tf.math.multiply/Mul" for i in range(12))
    g = helper.make_graph([helper.make_node("HardSwish", ["x"], ["h"], name=name),
                           helper.make_node("Relu", ["h"], ["y"])],
                          "old", [helper.make_tensor_value_info("x", TensorProto.FLOAT,
                                                                [1, 3, 8, 8])],
                          [helper.make_tensor_value_info("y", TensorProto.FLOAT, None)])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
    m.ir_version = 7
    onnx.save(m, str(tmp_path / "old.onnx"))
    with pytest.raises(ConfigError) as info:
        analyze(tmp_path / "old.onnx")
    text = str(info.value)
    assert "does not run in ONNX Runtime" in text
    assert re.search(r"HardSwish.*(domain_version|opset|version).*13", text.split("(", 1)[1])
