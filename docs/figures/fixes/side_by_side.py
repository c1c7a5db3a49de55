"""Before/after pictures of the figure fixes: the same figure from the
previous and the current `ftsmc`, side by side, each scaled to 560 px wide,
"before" on the left. Optional crop boxes (fractions of width and height)
pick the region a defect sits in.

    python docs/figures/fixes/side_by_side.py BEFORE.png AFTER.png OUT.png [x0 y0 x1 y1 [x0 y0 x1 y1]]

Needs Pillow (installed with matplotlib).
"""

from __future__ import annotations

import sys
from typing import List, Optional, Tuple

from PIL import Image, ImageDraw

WIDTH = 560


def load(path: str, box: Optional[Tuple[float, float, float, float]]) -> Image.Image:
    im = Image.open(path).convert("RGB")
    if box is not None:
        w, h = im.size
        im = im.crop((int(box[0] * w), int(box[1] * h), int(box[2] * w), int(box[3] * h)))
    scale = WIDTH / im.size[0]
    return im.resize((WIDTH, max(1, round(im.size[1] * scale))), Image.LANCZOS)


def main(args: List[str]) -> None:
    before_path, after_path, out = args[:3]
    boxes = [float(v) for v in args[3:]]
    b_box = tuple(boxes[:4]) if len(boxes) >= 4 else None
    a_box = tuple(boxes[4:8]) if len(boxes) >= 8 else b_box
    before, after = load(before_path, b_box), load(after_path, a_box)  # type: ignore[arg-type]
    label = 22
    h = max(before.size[1], after.size[1]) + label
    canvas = Image.new("RGB", (2 * WIDTH + 10, h), "white")
    canvas.paste(before, (0, label))
    canvas.paste(after, (WIDTH + 10, label))
    draw = ImageDraw.Draw(canvas)
    draw.text((4, 4), "before", fill=(180, 0, 0))
    draw.text((WIDTH + 14, 4), "after", fill=(0, 120, 0))
    canvas.quantize(colors=96).save(out, optimize=True)


if __name__ == "__main__":
    main(sys.argv[1:])
