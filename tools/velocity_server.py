#!/usr/bin/python3
"""Reference velocity-field server for doasido's guided tracker.

Speaks the protocol of recon/track/velocity_server.h over stdin/stdout and answers
with the Gaussian-mixture stand-in (recon/track/gaussian_mixture_flow.h), read
from an .npz file that `doasido` writes (recon/mixture_file.h):
  weights (F, K)  float64, 0 for an unused mode slot
  means   (F, K, D) float64
  sigmas  (F, K)  float64
  shape_dim ()    int64

A wrapper for a real model (SAM 3D) keeps the framing and the hello and
replaces `velocity` / `divergence` with calls to the network.

    tools/velocity_server.py MODES.npz [--misbehave die|garbage|version|nan]

--misbehave makes the server fail on purpose after the hello (tests).
Needs only Debian's python3-numpy.
"""
import json
import struct
import sys

import numpy as np

PROTOCOL = 1


def read_exact(stream, n):
    data = stream.read(n)
    if data is None or len(data) < n:
        sys.exit(0)  # doasido closed the pipe
    return data


def receive(stream):
    (header_len,) = struct.unpack("<I", read_exact(stream, 4))
    header = json.loads(read_exact(stream, header_len).decode("utf-8"))
    (payload_len,) = struct.unpack("<I", read_exact(stream, 4))
    payload = np.frombuffer(read_exact(stream, payload_len), dtype="<f8") if payload_len else None
    return header, payload


def send(stream, header, payload=None):
    text = json.dumps(header).encode("utf-8")
    body = b"" if payload is None else np.ascontiguousarray(payload, dtype="<f8").tobytes()
    stream.write(struct.pack("<I", len(text)) + text + struct.pack("<I", len(body)) + body)
    stream.flush()


class Mixture:
    def __init__(self, path):
        f = np.load(path)
        self.weights, self.means, self.sigmas = f["weights"], f["means"], f["sigmas"]
        self.shape_dim = int(f["shape_dim"])
        self.dim = self.means.shape[2]

    def _frame(self, k):
        used = self.weights[k] > 0
        w = self.weights[k][used]
        return w / w.sum(), self.means[k][used], self.sigmas[k][used]

    def _posterior(self, k, t, x):
        pi, mu, s = self._frame(k)
        var = (1 - t) ** 2 + t * t * s * s                       # (K,)
        r2 = ((x[:, None, :] - t * mu[None]) ** 2).sum(-1)        # (N, K)
        logw = np.log(pi)[None] - 0.5 * self.dim * np.log(var)[None] - 0.5 * r2 / var[None]
        logw -= logw.max(axis=1, keepdims=True)
        w = np.exp(logw)
        return w / w.sum(axis=1, keepdims=True), mu, s, var

    def velocity(self, k, t, x):
        w, mu, s, var = self._posterior(k, t, x)
        c = (t * s * s - (1 - t)) / var                            # (K,)
        u = mu[None] + c[None, :, None] * (x[:, None, :] - t * mu[None])  # (N, K, D)
        return (w[:, :, None] * u).sum(1)

    def divergence(self, k, t, x):
        w, mu, s, var = self._posterior(k, t, x)
        p = slice(self.shape_dim, self.dim)
        c = (t * s * s - (1 - t)) / var
        xp, mup = x[:, p], mu[:, p]
        u = mup[None] + c[None, :, None] * (xp[:, None, :] - t * mup[None])
        g = -(xp[:, None, :] - t * mup[None]) / var[None, :, None]
        g_mean = (w[:, :, None] * g).sum(1, keepdims=True)
        cross = (w * (u * (g - g_mean)).sum(-1)).sum(1)
        return (self.dim - self.shape_dim) * (w * c[None]).sum(1) + cross


def main():
    args = sys.argv[1:]
    misbehave = None
    if "--misbehave" in args:
        i = args.index("--misbehave")
        misbehave = args[i + 1]
        del args[i:i + 2]
    if len(args) != 1:
        sys.stderr.write(__doc__)
        sys.exit(2)
    model = Mixture(args[0])
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer
    header, _ = receive(stdin)
    if header.get("type") != "hello":
        send(stdout, {"type": "error", "message": "expected hello"})
        sys.exit(1)
    send(stdout, {"type": "hello", "protocol": PROTOCOL + (1 if misbehave == "version" else 0),
                  "shape_dim": model.shape_dim, "pose_dim": model.dim - model.shape_dim,
                  "frames": int(model.weights.shape[0]), "divergence": True})
    while True:
        header, payload = receive(stdin)
        kind = header.get("type")
        if kind == "bye":
            return
        if misbehave == "die":
            sys.stderr.write("velocity_server: dying on purpose\n")
            sys.exit(3)
        if misbehave == "garbage":
            stdout.write(b"\xff\xff\xff\x7fnot a frame")
            stdout.flush()
            continue
        rows, cols, k, t = header["rows"], header["cols"], header["frame"], header["t"]
        if not 0 <= k < model.weights.shape[0]:
            send(stdout, {"type": "error", "message": f"no frame {k}"})
            continue
        x = payload.reshape(rows, cols)
        if kind == "velocity":
            v = model.velocity(k, t, x)
            if misbehave == "nan":
                v[0, 0] = np.nan
            send(stdout, {"type": "velocity", "rows": rows, "cols": cols}, v)
        elif kind == "divergence":
            send(stdout, {"type": "divergence", "rows": rows, "cols": 1}, model.divergence(k, t, x))
        else:
            send(stdout, {"type": "error", "message": f"unknown request {kind!r}"})


if __name__ == "__main__":
    main()
