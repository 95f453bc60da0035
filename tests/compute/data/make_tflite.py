"""Writes tiny_cnn.tflite and tiny_cnn_int8.tflite beside this file: the .tflite models
tests/compute/test_compute_profile.py times with LiteRT (the test suite itself does not
need TensorFlow). A small CNN, NHWC 1x64x64x3: Conv2D 8 (3x3, ReLU), Conv2D 16 (3x3,
stride 2, ReLU), global average pooling, Dense 4; seeded weights. The second file is the
same network quantized to full integer (int8 input and output) by TFLiteConverter with a
seeded representative dataset, as for a Coral or a Pi.

    python -m venv /tmp/tf && /tmp/tf/bin/pip install tensorflow-cpu
    /tmp/tf/bin/python tests/compute/data/make_tflite.py

Written with tensorflow-cpu 2.21.0. tiny_cnn_int8_tf2onnx.onnx is the int8 model converted
to ONNX as teams convert a TF Lite model (a QDQ graph; tests/compute/test_quantized_models.py),
with tf2onnx 1.16.1 under tensorflow-cpu 2.15.1 (tf2onnx does not install with 2.21):

    python -m tf2onnx.convert --tflite tests/compute/data/tiny_cnn_int8.tflite \
        --output tests/compute/data/tiny_cnn_int8_tf2onnx.onnx --opset 13
"""

from pathlib import Path

import numpy as np
import tensorflow as tf

HERE = Path(__file__).resolve().parent


def main() -> None:
    tf.keras.utils.set_random_seed(0)
    model = tf.keras.Sequential([
        tf.keras.Input((64, 64, 3), batch_size=1),
        tf.keras.layers.Conv2D(8, 3, padding="same", activation="relu"),
        tf.keras.layers.Conv2D(16, 3, strides=2, padding="same", activation="relu"),
        tf.keras.layers.GlobalAveragePooling2D(),
        tf.keras.layers.Dense(4),
    ])
    conv = tf.lite.TFLiteConverter.from_keras_model(model)
    (HERE / "tiny_cnn.tflite").write_bytes(conv.convert())
    rng = np.random.default_rng(0)

    def representative():
        for _ in range(16):
            yield [rng.random((1, 64, 64, 3), dtype=np.float32)]
    conv = tf.lite.TFLiteConverter.from_keras_model(model)
    conv.optimizations = [tf.lite.Optimize.DEFAULT]
    conv.representative_dataset = representative
    conv.target_spec.supported_ops = [tf.lite.OpsSet.TFLITE_BUILTINS_INT8]
    conv.inference_input_type = tf.int8
    conv.inference_output_type = tf.int8
    (HERE / "tiny_cnn_int8.tflite").write_bytes(conv.convert())


if __name__ == "__main__":
    main()
