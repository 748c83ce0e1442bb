#!/usr/bin/python3
"""Reads a pyrocam temperature recording into a NumPy array in degrees Celsius.

A recording (pipelines/record.sh) is a folder of FFV1/Matroska segments, temperature-NNNNN.mkv,
of 16-bit codes: kelvin x 10, 0 = no reading. This decodes them in order with GStreamer and
returns an array of shape (frames, height, width), float32 degC, NaN where there is no reading.

    examples/read_recording.py out/run1                  # per-frame statistics on stdout
    examples/read_recording.py out/run1 --save t.npy     # also the array, for numpy.load
    examples/read_recording.py out/run1/temperature-00002.mkv   # one segment

Needs python3-gi, gir1.2-gstreamer-1.0, gir1.2-gst-plugins-base-1.0 and python3-numpy (Debian 12
packages; run it with /usr/bin/python3). Exit status 1 with a message for a folder that is not a
recording or a segment that does not decode; a last segment that is empty or cut short (a
recording killed as it began) is left out with a warning.
"""
import argparse
import glob
import os
import sys

import gi

gi.require_version("Gst", "1.0")
from gi.repository import Gst  # noqa: E402
import numpy as np  # noqa: E402


def read_segment(path):
    """The frames of one segment as uint16 arrays (height, width), and the segment's comment tag."""
    pipeline = Gst.parse_launch(
        "filesrc name=src ! matroskademux ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! "
        "appsink name=out sync=false")
    pipeline.get_by_name("src").set_property("location", path)
    sink = pipeline.get_by_name("out")
    comment = []

    def keep_comment(pad, info):
        event = info.get_event()
        if event.type == Gst.EventType.TAG:
            found, value = event.parse_tag().get_string(Gst.TAG_COMMENT)
            if found:
                comment.append(value)
        return Gst.PadProbeReturn.OK

    sink.get_static_pad("sink").add_probe(Gst.PadProbeType.EVENT_DOWNSTREAM, keep_comment)
    bus = pipeline.get_bus()
    pipeline.set_state(Gst.State.PLAYING)
    frames, problem = [], None
    try:
        while True:
            sample = sink.emit("try-pull-sample", 100 * Gst.MSECOND)
            if sample is None:
                msg = bus.pop_filtered(Gst.MessageType.ERROR)
                if msg is not None:
                    problem = f"{path}: {msg.parse_error()[0].message}"
                    break
                if sink.get_property("eos"):
                    break
                continue
            s = sample.get_caps().get_structure(0)
            width, height = s.get_value("width"), s.get_value("height")
            stride = (2 * width + 3) // 4 * 4  # GRAY16 rows are padded to 4 bytes
            buf = sample.get_buffer()
            ok, info = buf.map(Gst.MapFlags.READ)
            if not ok:
                raise RuntimeError(f"{path}: cannot read a frame")
            try:
                rows = np.frombuffer(info.data, dtype="<u2", count=stride // 2 * height)
                frames.append(rows.reshape(height, stride // 2)[:, :width].copy())
            finally:
                buf.unmap(info)
    finally:
        pipeline.set_state(Gst.State.NULL)
    if problem is None and not frames:
        problem = f"{path}: no frames"
    return frames, (comment[-1] if comment else ""), problem


SEGMENT_PREFIX, SEGMENT_SUFFIX = "temperature-", ".mkv"


def segment_digits(path):
    """What stands between the prefix and the suffix of a segment's name (record.sh's number)."""
    return os.path.basename(path)[len(SEGMENT_PREFIX):-len(SEGMENT_SUFFIX)]


def read_recording(folder):
    """(degC array (frames, height, width) float32 with NaN = no reading, the comment tag)."""
    Gst.init(None)
    if os.path.isfile(folder):  # one segment
        segments = [folder]
    elif not os.path.isdir(folder):
        raise RuntimeError(f"{folder}: no such recording (neither a folder nor a file)")
    else:
        # By number: temperature-100000 comes after temperature-99999.
        def number(p):
            digits = segment_digits(p)
            return (0, int(digits), p) if digits.isdigit() else (1, 0, p)
        pattern = os.path.join(glob.escape(folder), SEGMENT_PREFIX + "*" + SEGMENT_SUFFIX)
        segments = sorted(glob.glob(pattern), key=number)
    if not segments:
        raise RuntimeError(f"{folder}: not a recording (no temperature-NNNNN.mkv segments)")
    # Frame k is the k-th of the recording only if no segment is missing from the numbering.
    numbers = [int(segment_digits(p)) for p in segments if segment_digits(p).isdigit()]
    for a, b in zip(numbers, numbers[1:]):
        if b != a + 1:
            raise RuntimeError(f"{folder}: temperature-{a + 1:05d}.mkv is missing (the segments "
                               f"jump to temperature-{b:05d}.mkv)")
    codes, comment = [], ""
    for k, path in enumerate(segments):
        frames, tag, problem = read_segment(path)
        comment = tag or comment
        codes.extend(frames)
        if problem is None:
            continue
        # A recording killed as a segment began, or while it was written, leaves its last
        # segment empty or cut short: the segments before it, and what of it decoded, remain.
        if k == len(segments) - 1 and codes:
            print(f"warning: {problem}; the recording's last segment, cut short when it "
                  f"stopped: {len(frames)} of its frames read", file=sys.stderr)
            break
        raise RuntimeError(problem)
    if "quantity=" in comment and "quantity=temperature" not in comment:
        raise RuntimeError(f"{folder}: not temperatures ({comment})")
    codes = np.stack(codes)
    celsius = codes.astype(np.float32) / np.float32(10) - np.float32(273.15)
    celsius[codes == 0] = np.nan
    return celsius, comment


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "recording", help="recording folder (temperature-NNNNN.mkv segments), or one segment")
    parser.add_argument("--save", help="write the degC array to this .npy file")
    args = parser.parse_args()
    try:
        celsius, comment = read_recording(args.recording)
    except RuntimeError as e:
        print(f"read_recording: {e}", file=sys.stderr)
        return 1
    frames, height, width = celsius.shape
    print(f"# {frames} frames of {width}x{height}; {comment or 'no pyrocam tags'}")
    print("index,valid_fraction,min_c,median_c,max_c")
    for i, frame in enumerate(celsius):
        valid = frame[~np.isnan(frame)]
        if valid.size:
            print(f"{i},{valid.size / frame.size:.6f},{valid.min():.2f},{np.median(valid):.2f},"
                  f"{valid.max():.2f}")
        else:
            print(f"{i},0.000000,,,")
    if args.save:
        np.save(args.save, celsius)
    return 0


if __name__ == "__main__":
    sys.exit(main())
