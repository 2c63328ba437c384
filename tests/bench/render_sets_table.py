#!/usr/bin/env python3
"""Tables of docs/render.md's section "Particle sets of 50k to 4M" (issue 37), from the outputs of
tests/bench/render_sets_docs.sh: render_sets_table.py RUN_DIR IMAGES_DIR

RUN_DIR holds <set>.<method>.txt (fluiddemo render's output), <set>.<method>.png, .seconds, and
tiles.<WxH>.txt. Prints Markdown. PSNR is over RGB against the mesh's image of the same set; a
method's water mask is every pixel whose RGB differs from the backdrop alone (method none) by
more than 2/255; IoU compares it with the mesh's mask. Also writes side-by-side pictures (2x2:
mesh, screen_space / raycast, voxel) of the sets named in PICTURES to IMAGES_DIR. Plain Python
(zlib PNG reading and writing), no numpy.
"""
import math
import os
import re
import struct
import sys
import zlib

METHODS = ["mesh", "screen_space", "raycast", "voxel"]
PICTURES = ["pool_1000000", "spray_1000000", "pool_4000000"]


def read_png(path):
    data = open(path, "rb").read()
    pos, idat = 8, b""
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
    ch = {2: 3, 6: 4}[ctype]
    raw, stride = zlib.decompress(idat), w * ch
    out, prev, i = bytearray(), bytearray(stride), 0
    for _ in range(h):
        f, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        if f == 1:
            for x in range(ch, stride):
                line[x] = (line[x] + line[x - ch]) & 255
        elif f == 2:
            for x in range(stride):
                line[x] = (line[x] + prev[x]) & 255
        elif f == 3:
            for x in range(stride):
                line[x] = (line[x] + ((line[x - ch] if x >= ch else 0) + prev[x]) // 2) & 255
        elif f == 4:
            for x in range(stride):
                a = line[x - ch] if x >= ch else 0
                b, c = prev[x], (prev[x - ch] if x >= ch else 0)
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    if ch == 4:
        del out[3::4]
    return w, h, bytes(out)


def write_png(path, w, h, rgb):
    raw = b"".join(b"\x00" + rgb[y * w * 3:(y + 1) * w * 3] for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def psnr(a, b):
    se = sum((x - y) * (x - y) for x, y in zip(a, b))
    return float("inf") if se == 0 else 10 * math.log10(255.0 * 255.0 * len(a) / se)


def mask(img, bg):
    return [max(abs(img[i] - bg[i]), abs(img[i + 1] - bg[i + 1]), abs(img[i + 2] - bg[i + 2])) > 2
            for i in range(0, len(img), 3)]


def parse(path):
    out = {"stages": {}, "notes": []}
    if not os.path.exists(path):
        return None
    for line in open(path):
        m = re.match(r"^\s+(\S.*?)\s+([0-9.]+) ms$", line.rstrip())
        if m:
            out["stages"][m.group(1).strip()] = float(m.group(2))
        m = re.search(r"GPU memory\s+([0-9.]+) MiB", line)
        if m:
            out["mib"] = float(m.group(1))
        m = re.search(r"peak memory \(process\)\s+([0-9.]+) MiB", line)
        if m:
            out["rss"] = float(m.group(1))
        for key in ("voxel grid", "voxel memory", "raycast pool", "triangles", "particles splatted"):
            if key in line:
                out["notes"].append(line.strip())
        if line.startswith("render "):
            out["head"] = line.strip()
    return out


def main():
    run, images = sys.argv[1], sys.argv[2]
    sets = sorted({f.split(".")[0] for f in os.listdir(run) if f.endswith(".none.txt")},
                  key=lambda s: (int(s.split("_")[1]), s))
    print("| set | particles | method | seconds (process) | stages, ms | GPU MiB | process peak MiB | PSNR vs mesh dB | water IoU vs mesh | water pixels |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    notes = []
    for s in sets:
        kind, n = s.split("_")
        bg_png = os.path.join(run, f"{s}.none.png")
        bg = read_png(bg_png)[2] if os.path.exists(bg_png) else None
        ref = None
        for m in METHODS:
            info = parse(os.path.join(run, f"{s}.{m}.txt"))
            sec_path = os.path.join(run, f"{s}.{m}.seconds")
            seconds = open(sec_path).read().split()[0] if os.path.exists(sec_path) else "-"
            png = os.path.join(run, f"{s}.{m}.png")
            if info is None or "head" not in info or not os.path.exists(png):
                why = open(sec_path).read().split(None, 1)[1].strip() if os.path.exists(sec_path) and len(open(sec_path).read().split(None, 1)) > 1 else "not run"
                print(f"| {kind} | {int(n):,} | {m} | {seconds} | {why} | - | - | - | - | - |")
                continue
            img = read_png(png)[2]
            msk = mask(img, bg) if bg else None
            if m == "mesh":
                ref = (img, msk)
            stages = ", ".join(f"{k} {v:.0f}" for k, v in info["stages"].items()
                               if k not in ("spacing estimate",) and not k.startswith("all frames"))
            p = f"{psnr(img, ref[0]):.2f}" if ref and m != "mesh" else "-"
            iou = "-"
            if ref and msk and m != "mesh":
                both = sum(1 for a, b in zip(msk, ref[1]) if a and b)
                either = sum(1 for a, b in zip(msk, ref[1]) if a or b)
                iou = f"{both / either:.3f}" if either else "-"
            rss = f"{info['rss']:.0f}" if "rss" in info else "-"
            print(f"| {kind} | {int(n):,} | {m} | {seconds} | {stages} | {info.get('mib', 0):.1f} | {rss} | {p} | {iou} | "
                  f"{sum(msk) if msk else '-'} |")
            for note in info["notes"]:
                notes.append(f"- {kind} {int(n):,}, {m}: {note}")
    print()
    print("What the runs printed besides the stages (`fluiddemo render`'s own lines):")
    print()
    print("\n".join(notes))
    print()
    # Table 1 of the paper on this machine.
    tiles = sorted((f for f in os.listdir(run) if f.startswith("tiles.") and f.endswith(".txt")),
                   key=lambda f: int(f.split(".")[1].split("x")[0]) * int(f.split(".")[1].split("x")[1]))
    if tiles:
        print("| tile | tiles | tile grid MiB | splat ms | compress ms | splat + compress ms |")
        print("|---|---|---|---|---|---|")
        for f in tiles:
            info = parse(os.path.join(run, f))
            if info is None or "splat" not in info["stages"]:
                continue
            grid = next((l for l in info["notes"] if l.startswith("voxel grid")), "")
            mem = next((l for l in info["notes"] if l.startswith("voxel memory")), "")
            count = re.search(r"tiles (\d+) of", grid)
            mib = re.search(r"tile grid ([0-9.]+) MiB", mem)
            sp, co = info["stages"]["splat"], info["stages"]["compress"]
            print(f"| {f.split('.')[1]} | {count.group(1) if count else '-'} | {mib.group(1) if mib else '-'} | "
                  f"{sp:.0f} | {co:.0f} | {sp + co:.0f} |")
        print()
    for s in PICTURES:
        pngs = [os.path.join(run, f"{s}.{m}.png") for m in METHODS]
        if not all(os.path.exists(p) for p in pngs):
            continue
        ims = [read_png(p) for p in pngs]
        w, h = ims[0][0], ims[0][1]
        buf = bytearray(w * 2 * h * 2 * 3)
        for k, (_, _, rgb) in enumerate(ims):
            ox, oy = (k % 2) * w, (k // 2) * h
            for y in range(h):
                row = ((oy + y) * 2 * w + ox) * 3
                buf[row:row + w * 3] = rgb[y * w * 3:(y + 1) * w * 3]
        write_png(os.path.join(images, f"render_sets_{s}.png"), 2 * w, 2 * h, bytes(buf))


if __name__ == "__main__":
    main()
