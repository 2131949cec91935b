"""Writes the layered test files as other programs write them, and what each should
look like flattened (PNG): PSDs by psd-tools (its own composite as the reference),
OpenRaster files laid out as Krita writes them (composited here with Pillow).

    pip install psd-tools && python3 make.py
"""
import io
import zipfile

import numpy as np
from PIL import Image
from psd_tools import PSDImage
from psd_tools.api.layers import Group, PixelLayer
from psd_tools.constants import BlendMode, Compression


def blob(w, h, rgb, alpha=255, hole=False):
    a = np.zeros((h, w, 4), np.uint8)
    a[..., :3] = rgb
    a[..., 3] = alpha
    if hole:
        a[h // 3 : 2 * h // 3, w // 3 : 2 * w // 3, 3] = 0
    # A soft edge, so that partial alpha is exercised.
    a[0, :, 3] //= 2
    return Image.fromarray(a, "RGBA")


def psd_8bit():
    psd = PSDImage.new("RGBA", (64, 48), depth=8)
    ground = PixelLayer.frompil(blob(64, 20, (40, 90, 200)), psd, "ground", top=28, left=0)
    psd.append(ground)
    arm = PixelLayer.frompil(blob(20, 10, (220, 30, 30), alpha=200), psd, "arm", top=5, left=10)
    arm.opacity = 128
    psd.append(arm)
    hidden = PixelLayer.frompil(blob(30, 30, (0, 255, 0)), psd, "hidden", top=0, left=0)
    hidden.visible = False
    psd.append(hidden)
    body = Group.new(psd, "body")
    torso = PixelLayer.frompil(blob(16, 16, (240, 220, 40), hole=True), body, "torso", top=20, left=30,
                               compression=Compression.RAW)
    body.append(torso)
    # Reaches past the canvas: clipped.
    leg = PixelLayer.frompil(blob(30, 20, (120, 60, 20)), body, "leg", top=40, left=50,
                             compression=Compression.ZIP)
    body.append(leg)
    body.opacity = 200
    shade = PixelLayer.frompil(blob(12, 12, (10, 10, 10), alpha=120), psd, "shade", top=2, left=45)
    shade.blend_mode = BlendMode.MULTIPLY
    psd.append(shade)
    return psd


def psd_16bit():
    psd = PSDImage.new("RGBA", (40, 30), depth=16)
    a = np.zeros((30, 40, 4), np.uint16)
    a[..., 0] = np.linspace(0, 65535, 40, dtype=np.uint16)[None, :]
    a[..., 1] = 1234
    a[..., 2] = 40000
    a[..., 3] = 65535
    psd.append(PixelLayer.fromarray(a, psd, "gradient"))
    b = np.zeros((10, 12, 4), np.uint16)
    b[..., 0] = 65535
    b[..., 3] = 30000
    psd.append(PixelLayer.fromarray(b, psd, "glaze", top=8, left=20))
    return psd


def krita_ora(path, layers, size, stacks):
    """`layers`: (name, image, x, y, opacity, visible), top first, inside `stacks`."""
    w, h = size
    xml = [
        "<?xml version='1.0' encoding='UTF-8'?>",
        '<!DOCTYPE image>',
        f'<image xres="300" h="{h}" yres="300" version="0.0.1" w="{w}" name="">',
        ' <stack composite-op="svg:src-over" x="0" name="root" y="0" visibility="visible" opacity="1" isolation="isolate">',
    ]
    files = {}
    for i, item in enumerate(stacks):
        if item[0] == "stack":
            _, name, x, y, opacity, visible, children = item
            xml.append(f'  <stack composite-op="svg:src-over" x="{x}" name="{name}" y="{y}" '
                       f'visibility="{"visible" if visible else "hidden"}" opacity="{opacity}" isolation="isolate">')
            for j, (lname, im, lx, ly, lop, lvis) in enumerate(children):
                src = f"data/layer{i}_{j}.png"
                files[src] = im
                xml.append(f'   <layer composite-op="svg:src-over" x="{lx}" name="{lname}" y="{ly}" '
                           f'visibility="{"visible" if lvis else "hidden"}" opacity="{lop}" src="{src}"/>')
            xml.append("  </stack>")
        else:
            lname, im, lx, ly, lop, lvis = item
            src = f"data/layer{i}.png"
            files[src] = im
            xml.append(f'  <layer composite-op="svg:src-over" x="{lx}" name="{lname}" y="{ly}" '
                       f'visibility="{"visible" if lvis else "hidden"}" opacity="{lop}" src="{src}"/>')
    xml += [" </stack>", "</image>", ""]
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(zipfile.ZipInfo("mimetype"), "image/openraster", compress_type=zipfile.ZIP_STORED)
        z.writestr("stack.xml", "\n".join(xml), compress_type=zipfile.ZIP_DEFLATED)
        for src, im in files.items():
            buf = io.BytesIO()
            im.save(buf, "PNG")
            z.writestr(src, buf.getvalue(), compress_type=zipfile.ZIP_STORED)


def composite(size, flat):
    """`flat`: (image, x, y, opacity, visible), bottom first."""
    out = Image.new("RGBA", size, (0, 0, 0, 0))
    for im, x, y, opacity, visible in flat:
        if not visible:
            continue
        a = np.array(im).astype(np.float64)
        a[..., 3] = np.round(a[..., 3] * opacity)
        layer = Image.new("RGBA", size, (0, 0, 0, 0))
        layer.paste(Image.fromarray(a.astype(np.uint8), "RGBA"), (x, y))
        out = Image.alpha_composite(out, layer)
    return out


def main():
    p8 = psd_8bit()
    p8.save("psd-tools-8bit.psd")
    PSDImage.open("psd-tools-8bit.psd").composite(force=True).convert("RGBA").save("psd-tools-8bit.png")
    p16 = psd_16bit()
    p16.save("psd-tools-16bit.psd")

    tail = blob(30, 8, (200, 120, 40))
    body = blob(24, 20, (90, 160, 90), hole=True)
    head = blob(10, 10, (250, 200, 180), alpha=230)
    ghost = blob(10, 10, (255, 0, 255))
    # Top first, as stack.xml lists them; a group offset by (4, 2) at 0.5 opacity.
    stacks = [
        ("head", head, 30, 4, 1.0, True),
        ("stack", "torso group", 4, 2, 0.5, True, [("body", body, 20, 10, 1.0, True)]),
        ("ghost", ghost, 0, 0, 1.0, False),
        ("tail", tail, 40, 26, 0.75, True),
    ]
    krita_ora("krita-like.ora", None, (64, 40), stacks)
    flat = [
        (tail, 40, 26, 0.75, True),
        (ghost, 0, 0, 1.0, False),
        (body, 24, 12, 0.5, True),
        (head, 30, 4, 1.0, True),
    ]
    composite((64, 40), flat).save("krita-like.png")


if __name__ == "__main__":
    main()
