#!/usr/bin/env python3
"""Draws the sample layered character, assets/puppet.ora: a cut-out cat in eight
layers, each part drawn whole on its own layer (an arm goes on under the body, as an
artist draws it for a puppet), written as Krita writes OpenRaster (a stored
`mimetype` first, `stack.xml`, a PNG per layer cropped to its pixels with its offset,
`mergedimage.png` and a thumbnail).

    python3 scripts/puppet_ora.py assets/puppet.ora

Needs Pillow. Deterministic: the same file every run.
"""

import io
import math
import sys
import zipfile

from PIL import Image, ImageDraw, ImageFilter

W, H = 640, 720
SS = 4  # drawn at 4x, then reduced: smooth edges

INK = (58, 40, 34, 255)
FUR = (236, 150, 62, 255)
FUR_DARK = (208, 118, 44, 255)
CREAM = (250, 228, 196, 255)
PINK = (238, 150, 160, 255)


def canvas():
    return Image.new("RGBA", (W * SS, H * SS), (0, 0, 0, 0))


def s(*p):
    return [v * SS for v in p]


def limb(draw, a, b, width, fill, paw=None):
    """A rounded limb from `a` to `b` with an ink outline, and a paw at `b`."""
    (ax, ay), (bx, by) = a, b
    line = 5
    for w, colour in ((width + 2 * line, INK), (width, fill)):
        draw.line(s(ax, ay, bx, by), fill=colour, width=w * SS)
        for x, y in (a, b):
            r = w / 2
            draw.ellipse(s(x - r, y - r, x + r, y + r), fill=colour)
    if paw:
        r = width * 0.62
        draw.ellipse(s(bx - r - line, by - r - line, bx + r + line, by + r + line), fill=INK)
        draw.ellipse(s(bx - r, by - r, bx + r, by + r), fill=paw)


def stripe(draw, cx, cy, length, angle, width=7):
    dx, dy = math.cos(angle) * length / 2, math.sin(angle) * length / 2
    draw.line(s(cx - dx, cy - dy, cx + dx, cy + dy), fill=FUR_DARK, width=width * SS)


def tail():
    im = canvas()
    d = ImageDraw.Draw(im)
    points = [(400, 470), (470, 440), (520, 380), (540, 300), (525, 240)]
    for w, colour in ((40, INK), (30, FUR)):
        d.line([v * SS for p in points for v in p], fill=colour, width=w * SS, joint="curve")
        for x, y in (points[0], points[-1]):
            d.ellipse(s(x - w / 2, y - w / 2, x + w / 2, y + w / 2), fill=colour)
    for x, y in ((505, 405), (533, 330)):
        stripe(d, x, y, 26, math.radians(30))
    d.ellipse(s(512, 226, 538, 256), fill=CREAM)
    return "tail", im


def back_arm():
    im = canvas()
    limb(ImageDraw.Draw(im), (360, 330), (430, 450), 44, FUR_DARK, paw=CREAM)
    return "arm (back)", im


def back_leg():
    im = canvas()
    limb(ImageDraw.Draw(im), (350, 500), (372, 640), 52, FUR_DARK, paw=CREAM)
    return "leg (back)", im


def body():
    im = canvas()
    d = ImageDraw.Draw(im)
    box = (232, 290, 408, 560)
    d.ellipse(s(box[0] - 5, box[1] - 5, box[2] + 5, box[3] + 5), fill=INK)
    d.ellipse(s(*box), fill=FUR)
    d.ellipse(s(268, 340, 372, 540), fill=CREAM)
    for y in (395, 430, 465):
        stripe(d, 248, y, 22, math.radians(-12))
        stripe(d, 392, y, 22, math.radians(12))
    return "body", im


def front_leg():
    im = canvas()
    limb(ImageDraw.Draw(im), (285, 500), (262, 645), 56, FUR, paw=CREAM)
    return "leg (front)", im


def head():
    im = canvas()
    d = ImageDraw.Draw(im)
    cx, cy, r = 320, 215, 105
    for ex in (-1, 1):
        ear = [(cx + ex * 22, cy - 80), (cx + ex * 92, cy - 128), (cx + ex * 100, cy - 24)]
        centre = (sum(p[0] for p in ear) / 3, sum(p[1] for p in ear) / 3)
        for shrink, colour in ((1.0, INK), (0.78, FUR), (0.45, PINK)):
            pts = [(centre[0] + (x - centre[0]) * shrink, centre[1] + (y - centre[1]) * shrink) for x, y in ear]
            d.polygon([v * SS for p in pts for v in p], fill=colour)
    d.ellipse(s(cx - r - 5, cy - r * 0.9 - 5, cx + r + 5, cy + r * 0.9 + 5), fill=INK)
    d.ellipse(s(cx - r, cy - r * 0.9, cx + r, cy + r * 0.9), fill=FUR)
    d.ellipse(s(cx - 55, cy + 5, cx + 55, cy + 85), fill=CREAM)
    for x in (-20, 0, 20):
        stripe(d, cx + x, cy - 78, 26, math.radians(90), width=6)
    for ex in (-1, 1):
        x = cx + ex * 42
        d.ellipse(s(x - 17, cy - 30, x + 17, cy + 8), fill=INK)
        d.ellipse(s(x - 6, cy - 24, x + 4, cy - 14), fill=(255, 255, 255, 255))
        for k in (-1, 0, 1):
            d.line(s(cx + ex * 50, cy + 40 + 7 * k, cx + ex * 118, cy + 32 + 16 * k), fill=INK, width=3 * SS)
    d.polygon(s(cx - 12, cy + 22, cx + 12, cy + 22, cx, cy + 36), fill=PINK)
    d.line(s(cx, cy + 36, cx, cy + 48), fill=INK, width=4 * SS)
    d.arc(s(cx - 24, cy + 36, cx, cy + 60), 0, 180, fill=INK, width=4 * SS)
    d.arc(s(cx, cy + 36, cx + 24, cy + 60), 0, 180, fill=INK, width=4 * SS)
    return "head", im


def front_arm():
    im = canvas()
    limb(ImageDraw.Draw(im), (268, 335), (180, 445), 48, FUR, paw=CREAM)
    return "arm (front)", im


def reduce(im):
    return im.filter(ImageFilter.GaussianBlur(SS / 3)).resize((W, H), Image.LANCZOS)


def cropped(im):
    box = im.getchannel("A").getbbox()
    return im.crop(box), box[0], box[1]


def main(path):
    # Bottom first.
    parts = [tail(), back_arm(), back_leg(), body(), front_leg(), head(), front_arm()]
    layers = [(name, *cropped(reduce(im))) for name, im in parts]
    merged = Image.new("RGBA", (W, H), (0, 0, 0, 0))
    for _, im, x, y in layers:
        sheet = Image.new("RGBA", (W, H), (0, 0, 0, 0))
        sheet.paste(im, (x, y))
        merged = Image.alpha_composite(merged, sheet)
    xml = [
        "<?xml version='1.0' encoding='UTF-8'?>",
        "<!DOCTYPE image>",
        f'<image xres="300" h="{H}" yres="300" version="0.0.1" w="{W}" name="puppet">',
        ' <stack composite-op="svg:src-over" x="0" name="root" y="0" '
        'visibility="visible" opacity="1" isolation="isolate">',
    ]
    files = {}
    for i, (name, im, x, y) in reversed(list(enumerate(layers))):
        src = f"data/layer{i}.png"
        files[src] = im
        xml.append(
            f'  <layer composite-op="svg:src-over" x="{x}" name="{name}" y="{y}" '
            f'visibility="visible" opacity="1" src="{src}"/>'
        )
    xml += [" </stack>", "</image>", ""]

    def png(im):
        buf = io.BytesIO()
        im.save(buf, "PNG", optimize=True)
        return buf.getvalue()

    thumb = merged.copy()
    thumb.thumbnail((256, 256))
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(zipfile.ZipInfo("mimetype"), "image/openraster", compress_type=zipfile.ZIP_STORED)
        z.writestr("stack.xml", "\n".join(xml), compress_type=zipfile.ZIP_DEFLATED)
        for src, im in files.items():
            z.writestr(src, png(im), compress_type=zipfile.ZIP_STORED)
        z.writestr("mergedimage.png", png(merged), compress_type=zipfile.ZIP_STORED)
        z.writestr("Thumbnails/thumbnail.png", png(thumb), compress_type=zipfile.ZIP_STORED)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "assets/puppet.ora")
