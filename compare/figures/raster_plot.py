"""A small plotting toolkit on PIL and numpy alone (no matplotlib): figures laid out in inches,
axes with a data -> pixel mapping, round ticks, lines, markers, discs, cells, text, legends,
colour maps and colour bars. compare.figures.quick_figures draws a run's pictures with it.

The data inside an axes box is drawn at SUPERSAMPLE times its pixels and scaled down (Image.reduce)
into the figure: that is the antialiasing of discs and slanted lines, which PIL's own drawing
lacks. Text (FreeType, antialiased itself), frames and ticks are drawn on the figure at its own
pixels: the whole figure at twice the size cost twice the time (filling, reducing and text at 4x
the pixels). A figure's pixels are those of dpi (150, as compare.figures), its sizes in inches and
points as matplotlib's, so that both renderers give pictures of the same size and proportions.
"""

import functools
import math
import os

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from compare.io import atomic_file
from compare.figures.png_file import SAVE_DPI, png_bytes_of_rows

# An axes' data drawn at twice the size, then averaged 2 x 2 (Image.reduce): antialiased edges.
SUPERSAMPLE = 2

# --------------------------------------------------------------------------- colours

# The named colours the pictures use (matplotlib's values).
NAMED = {"black": (0, 0, 0), "white": (255, 255, 255), "darkred": (139, 0, 0),
         "firebrick": (178, 34, 34), "steelblue": (70, 130, 180),
         "tab:blue": (31, 119, 180), "tab:orange": (255, 127, 14), "tab:green": (44, 160, 44),
         "tab:red": (214, 39, 40), "tab:purple": (148, 103, 189), "tab:brown": (140, 86, 75)}
TAB10 = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
         (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207)]

# Colour maps as a few stops, linearly interpolated: YlOrRd and RdBu are ColorBrewer's stops (as
# matplotlib's); viridis at 17 stops is within 6 of 255 of matplotlib's 256-entry table.
COLORMAPS = {
    "viridis": [(68, 1, 84), (72, 24, 106), (71, 45, 123), (66, 64, 134), (59, 82, 139),
                (51, 99, 141), (44, 114, 142), (38, 130, 142), (33, 145, 140), (31, 160, 136),
                (40, 174, 128), (63, 188, 115), (94, 201, 98), (132, 212, 75), (173, 220, 48),
                (216, 226, 25), (253, 231, 37)],
    "YlOrRd": [(255, 255, 204), (255, 237, 160), (254, 217, 118), (254, 178, 76), (253, 140, 60),
               (252, 77, 42), (226, 25, 28), (187, 0, 38), (128, 0, 38)],
    "RdBu_r": [(5, 48, 97), (32, 101, 171), (67, 147, 195), (144, 196, 221), (209, 229, 240),
               (247, 246, 246), (253, 219, 199), (243, 164, 129), (214, 96, 77), (177, 24, 43),
               (103, 0, 31)],
}


def rgb(colour):
    """An (r, g, b) tuple of 0..255 from a name of NAMED, a grey level string ('0.6', as
    matplotlib's), a tuple of 0..1 floats or of 0..255 ints."""
    if isinstance(colour, str):
        if colour in NAMED:
            return NAMED[colour]
        level = int(round(float(colour) * 255))
        return (level, level, level)
    c = tuple(colour)[:3]
    if all(isinstance(v, (float, np.floating)) for v in c):
        return tuple(int(round(v * 255)) for v in c)
    return tuple(int(v) for v in c)


def blend(colour, alpha, under=(255, 255, 255)):
    """colour drawn with opacity alpha over ``under`` (PIL draws opaque: alpha is blended here)."""
    c, u = rgb(colour), rgb(under)
    return tuple(int(round(alpha * a + (1 - alpha) * b)) for a, b in zip(c, u))


def colormap(name, fraction, lo=0.0, hi=1.0):
    """Colours (n, 3) uint8 of a map at fractions 0..1 (clipped), of its part lo..hi."""
    stops = np.asarray(COLORMAPS[name], float)
    at = np.linspace(0.0, 1.0, len(stops))
    f = lo + (hi - lo) * np.clip(np.asarray(fraction, float), 0.0, 1.0)
    return np.stack([np.interp(f, at, stops[:, k]) for k in range(3)], axis=-1).round().astype(np.uint8)


# --------------------------------------------------------------------------- fonts

FONT_NAME = "DejaVuSans.ttf"


def font_path():
    """DejaVu Sans: Debian's copy, else matplotlib's own (found without importing matplotlib);
    None if neither is there (then PIL's small bitmap font is used, at one size)."""
    path = os.path.join("/usr/share/fonts/truetype/dejavu", FONT_NAME)
    if os.path.exists(path):
        return path
    import importlib.util                                  # only here: 7 ms to import
    spec = importlib.util.find_spec("matplotlib")         # finds the package, does not import it
    if spec is not None and spec.origin:
        path = os.path.join(os.path.dirname(spec.origin), "mpl-data", "fonts", "ttf", FONT_NAME)
        if os.path.exists(path):
            return path
    return None


@functools.lru_cache(maxsize=None)
def font(size_px):
    """The font at size_px pixels (cached: loading a size costs about a millisecond)."""
    path = font_path()
    if path is None:
        return ImageFont.load_default()
    return ImageFont.truetype(path, max(1, int(round(size_px))))


def _encodable(fnt, s):
    """s as the font can draw it: PIL's bitmap fallback font has Latin-1 only ('?' for the rest:
    pi, minus signs)."""
    if isinstance(fnt, ImageFont.FreeTypeFont):
        return s
    return s.encode("latin-1", "replace").decode("latin-1")


@functools.lru_cache(maxsize=4096)
def measure(size_px, s):
    """text_size of s in the font of size_px (cached: tick labels repeat)."""
    fnt = font(size_px)
    return text_size(fnt, _encodable(fnt, s))


# Pixels left of a line's mask for glyphs that reach left of the pen (a negative bearing).
TEXT_MARGIN = 2


@functools.lru_cache(maxsize=4096)
def text_mask(size_px, s):
    """One line of text as a coverage mask ("L", FreeType's antialiasing), the pen at
    (TEXT_MARGIN, 0); cached: tick labels and panel titles repeat, and a mask pasted costs less
    than the text drawn again."""
    w, h = measure(size_px, s)
    fnt = font(size_px)
    mask = Image.new("L", (int(w) + 2 * TEXT_MARGIN + 1, int(h) + 1), 0)
    ImageDraw.Draw(mask).text((TEXT_MARGIN, 0), _encodable(fnt, s), fill=255, font=fnt)
    return mask


def text_size(fnt, s):
    """(width, height) of one line of text in pixels: the advance and the font's line height."""
    left, _, right, _ = fnt.getbbox(s or " ")
    ascent, descent = fnt.getmetrics() if hasattr(fnt, "getmetrics") else (fnt.getbbox("Ag")[3], 0)
    return right - min(left, 0), ascent + descent


# --------------------------------------------------------------------------- ticks


def nice_ticks(lo, hi, max_intervals=6, steps=(1, 2, 2.5, 5, 10)):
    """Round tick values in [lo, hi]: the step is the smallest of steps x 10^k that makes at most
    max_intervals intervals of the span (as matplotlib's MaxNLocator); e.g. 0..7.3 -> 0, 2, 4,
    6."""
    lo, hi = (lo, hi) if lo <= hi else (hi, lo)
    span = hi - lo
    if not span > 0 or not math.isfinite(span):
        return np.array([lo])
    raw = span / max_intervals
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in tuple(steps) + (10,) if m * mag >= raw * (1 - 1e-9))
    first, last = math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9)
    return np.arange(first, last + 1) * step


def tick_labels(values):
    """Labels of equally spaced ticks with the decimals their step needs ('0', '0.5', '1')."""
    values = np.asarray(values, float)
    if len(values) < 2:
        return [f"{v:g}" for v in values]
    step = float(np.min(np.diff(values)))
    text = f"{step:.6g}"
    if "e" in text:
        return [f"{v:.3g}" for v in values]
    decimals = len(text.split(".")[1]) if "." in text else 0
    out = []
    for v in values:
        s = f"{v:.{decimals}f}"
        s = s.lstrip("-") if float(s) == 0 else s
        out.append(s.replace("-", "\u2212"))                # matplotlib's minus sign
    return out


# --------------------------------------------------------------------------- dashes

DASHES = {"-": None, "--": (3.7, 1.6), ":": (1.0, 1.65), "-.": (6.4, 1.6, 1.0, 1.6)}   # in line widths


def dash_segments(points, pattern):
    """The pieces of a polyline (k, 2) that a dash pattern (on, off, ...) in pixels draws."""
    out, on, k, left = [], True, 0, pattern[0]
    current = [points[0]]
    for a, b in zip(points[:-1], points[1:]):
        seg = float(np.hypot(*(b - a)))
        pos = 0.0
        while seg - pos > left:
            pos += left
            p = a + (b - a) * (pos / seg)
            if on:
                current.append(p)
                out.append(np.array(current))
            current = [p]
            on = not on
            k = (k + 1) % len(pattern)
            left = pattern[k]
        left -= seg - pos
        if on:
            current.append(b)
        else:
            current = [b]
    if on and len(current) > 1:
        out.append(np.array(current))
    return out


# --------------------------------------------------------------------------- figure


class Figure:
    """A white picture of width x height inches at dpi. Layout positions are in inches from the
    top left corner, drawing positions in its pixels."""

    def __init__(self, width_in, height_in, dpi=SAVE_DPI):
        self.dpi = dpi
        self.scale = dpi                                         # pixels per inch
        self.size = (int(round(width_in * dpi)), int(round(height_in * dpi)))
        self.width_in, self.height_in = width_in, height_in
        self.image = Image.new("RGB", self.size, "white")
        self.draw = ImageDraw.Draw(self.image)
        self.all_axes = []                                       # in the order made

    def px(self, inches):
        """Inches as pixels."""
        return inches * self.scale

    def pt(self, points):
        """Points (1/72 inch: line widths, font sizes) as pixels."""
        return points / 72.0 * self.scale

    def text(self, x, y, s, size=10, ha="left", va="top", colour="black", rotate=False, align=None):
        """Text (lines split at newlines) at pixel (x, y); ha left/center/right, va
        top/center/bottom of the whole block, align (default ha) each line in the block;
        rotate=True writes it upward (a y-axis label)."""
        fnt = font(self.pt(size))
        lines = str(s).split("\n")
        sizes = [measure(self.pt(size), line) for line in lines]
        line_h = max(h for _, h in sizes)
        w, h = max(w for w, _ in sizes), line_h * len(lines)
        if rotate:
            block = Image.new("L", (int(w) + 2, int(h) + 2), 0)
            pen = ImageDraw.Draw(block)
            for k, (line, (lw, _)) in enumerate(zip(lines, sizes)):
                pen.text(((w - lw) / 2, k * line_h), _encodable(fnt, line), fill=255, font=fnt)
            block = block.transpose(Image.Transpose.ROTATE_90)
            bw, bh = block.size
            x0 = x - {"left": 0, "center": bw / 2, "right": bw}[ha]
            y0 = y - {"top": 0, "center": bh / 2, "bottom": bh}[va]
            self.image.paste(Image.new("RGB", block.size, rgb(colour)), (int(round(x0)), int(round(y0))), block)
            return
        y0 = y - {"top": 0, "center": h / 2, "bottom": h}[va]
        left = x - {"left": 0, "center": w / 2, "right": w}[ha]
        for k, (line, (lw, _)) in enumerate(zip(lines, sizes)):
            x0 = left + {"left": 0, "center": (w - lw) / 2, "right": w - lw}[align or ha]
            mask = text_mask(self.pt(size), line)
            self.image.paste(rgb(colour), (int(round(x0)) - TEXT_MARGIN, int(round(y0 + k * line_h))), mask)

    def text_width(self, s, size):
        """Drawn pixel width of one line of text at size points."""
        return measure(self.pt(size), s)[0]

    def axes(self, left, top, width, height, xlim=(0.0, 1.0), ylim=(0.0, 1.0), invert_y=False,
             supersample=SUPERSAMPLE):
        """Axes in the box left, top, width, height (inches) showing xlim x ylim."""
        box = tuple(int(round(self.px(v))) for v in (left, top, left + width, top + height))
        self.all_axes.append(Axes(self, box, xlim, ylim, invert_y, supersample=supersample))
        return self.all_axes[-1]

    def colorbar(self, left, top, width, height, colours, ticks, label, size=7, label_size=8):
        """A vertical colour bar in the box (inches): ``colours`` (n, 3) from bottom to top,
        ``ticks`` = [(fraction 0..1 up the bar, label)], ``label`` beside it at the right."""
        x0, y0 = int(round(self.px(left))), int(round(self.px(top)))
        x1, y1 = int(round(self.px(left + width))), int(round(self.px(top + height)))
        strip = Image.fromarray(np.ascontiguousarray(np.asarray(colours, np.uint8)[::-1, None, :]), "RGB")
        self.image.paste(strip.resize((x1 - x0, y1 - y0), Image.Resampling.NEAREST), (x0, y0))
        lw = max(1, int(round(self.pt(0.8))))
        self.draw.rectangle([x0, y0, x1, y1], outline=(0, 0, 0), width=lw)
        tick = self.pt(3.5)
        widest = 0
        for f, text in ticks:
            y = y1 - f * (y1 - y0)
            self.draw.line([(x1, y), (x1 + tick, y)], fill=(0, 0, 0), width=lw)
            self.text(x1 + tick + self.pt(3.5), y, text, size=size, va="center")
            widest = max(widest, self.text_width(text, size))
        self.text(x1 + tick + self.pt(7) + widest, (y0 + y1) / 2, label, size=label_size, ha="left",
                  va="center", rotate=True)

    def png(self):
        """The picture as PNG bytes (png_file), read from the image a strip of rows at a time."""
        w, h = self.size
        return png_bytes_of_rows(w, h, 3, lambda y0, y1: np.asarray(self.image.crop((0, y0, w, y1))), self.dpi)

    def save(self, path):
        """Write the PNG through path.tmp, renamed when complete: a killed process leaves no half
        file."""
        return atomic_file.write_bytes(path, self.png())


# --------------------------------------------------------------------------- axes


def _fig_width(fig, points):
    """A line width in points as whole figure pixels (at least one)."""
    return max(1, int(round(fig.pt(points))))


class Axes:
    """A box of a Figure that maps data (x, y) to pixels. Data is drawn on the box's own image at
    ``supersample`` times its pixels (so that it is clipped to the box, and antialiased when
    scaled down) and pasted into the figure by finish(), which also draws the frame, ticks, tick
    labels, axis labels and title. A twin (twin()) shares the image and x and has its own y,
    labelled on the right."""

    def __init__(self, fig, box, xlim, ylim, invert_y=False, image=None, supersample=SUPERSAMPLE):
        self.fig, self.box, self.ss = fig, box, supersample
        self.w, self.h = box[2] - box[0], box[3] - box[1]             # figure pixels
        self.W, self.H = self.w * supersample, self.h * supersample   # the drawing's pixels
        self.xlim, self.ylim, self.invert_y = tuple(map(float, xlim)), tuple(map(float, ylim)), invert_y
        self.image = image if image is not None else Image.new("RGB", (self.W, self.H), "white")
        self.draw = ImageDraw.Draw(self.image)
        self.owner = image is None
        self.xticks = self.yticks = None
        self._legend, self.finished = None, False

    # mapping -------------------------------------------------------------
    def x_px(self, x):
        """Data x as drawing pixels from the box's left edge (float, not rounded)."""
        x0, x1 = self.xlim
        return (np.asarray(x, float) - x0) / (x1 - x0) * self.W

    def y_px(self, y):
        """Data y as drawing pixels from the box's top edge: up is smaller, unless invert_y."""
        y0, y1 = self.ylim
        f = (np.asarray(y, float) - y0) / (y1 - y0)
        return f * self.H if self.invert_y else (1.0 - f) * self.H

    def figure_px(self, x, y):
        """Data (x, y) as pixels of the figure."""
        return self.box[0] + self.x_px(x) / self.ss, self.box[1] + self.y_px(y) / self.ss

    def twin(self, ylim):
        """Axes on the same box, image and x, with their own y (ticks on the right); made before
        finish(), which pastes the image the two draw on."""
        if self.finished:
            raise RuntimeError("raster_plot: twin() of axes already finished (their image is pasted)")
        return Axes(self.fig, self.box, self.xlim, ylim, image=self.image, supersample=self.ss)

    # drawing -------------------------------------------------------------
    def _width(self, points):
        """A line width in points as whole drawing pixels (at least one)."""
        return max(1, int(round(self.fig.pt(points) * self.ss)))

    def line(self, x, y, colour="black", width=1.5, style="-"):
        """A polyline through finite points (nan breaks it), solid or dashed ('--', ':', '-.')."""
        px, py = self.x_px(x), self.y_px(y)
        ok = np.isfinite(px) & np.isfinite(py)
        w, c = self._width(width), rgb(colour)
        pattern = DASHES.get(style)
        breaks = np.flatnonzero(np.diff(ok.astype(int)) != 0) + 1
        for run in np.split(np.arange(len(px)), breaks):
            if not len(run) or not ok[run[0]]:
                continue
            pts = np.column_stack([px[run], py[run]])
            if len(pts) == 1:
                continue
            pieces = [pts] if pattern is None else dash_segments(pts, [p * w for p in pattern])
            for piece in pieces:
                self.draw.line([tuple(p) for p in piece], fill=c, width=w, joint="curve")

    def step(self, x, y, **kw):
        """A step line, each value held to the next x (matplotlib's where='post')."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        xs = np.repeat(x, 2)[1:]
        ys = np.repeat(y, 2)[:-1]
        self.line(xs, ys, **kw)

    def markers(self, x, y, shape="o", size=6, face="black", edge=None, edge_width=1.0):
        """Markers of size points (across) at finite points: 'o' circle, 'v' '<' '>' triangles;
        face None leaves it hollow."""
        # a filled marker without an edge of its own has matplotlib's: its face colour, 1 pt wide
        r = self.fig.pt(size + (1.0 if face is not None and edge is None else 0.0)) * self.ss / 2
        fill = None if face is None else rgb(face)
        outline = None if edge is None else rgb(edge)
        ew = self._width(edge_width)
        tri = {"v": [(-1, -1), (1, -1), (0, 1)], "<": [(1, -1), (1, 1), (-1, 0)],
               ">": [(-1, -1), (-1, 1), (1, 0)], "^": [(-1, 1), (1, 1), (0, -1)]}
        for cx, cy in zip(self.x_px(x), self.y_px(y)):
            if not (np.isfinite(cx) and np.isfinite(cy)):
                continue
            if shape in tri:
                self.draw.polygon([(cx + r * a, cy + r * b) for a, b in tri[shape]], fill=fill, outline=outline)
            else:
                self.draw.ellipse([cx - r, cy - r, cx + r, cy + r], fill=fill, outline=outline,
                                  width=ew if outline else 0)

    def discs(self, x, y, r, faces=None, edge="0.5", edge_width=0.3):
        """Discs of radius r in data units (x scale), each with its face colour (n, 3) or none."""
        px, py = self.x_px(x), self.y_px(y)
        pr = np.asarray(r, float) * self.W / (self.xlim[1] - self.xlim[0])
        outline, ew = rgb(edge), self._width(edge_width)
        ellipse = self.draw.ellipse
        if faces is None:
            for cx, cy, cr in zip(px.tolist(), py.tolist(), pr.tolist()):
                ellipse((cx - cr, cy - cr, cx + cr, cy + cr), outline=outline, width=ew)
            return
        for cx, cy, cr, f in zip(px.tolist(), py.tolist(), pr.tolist(), map(tuple, np.asarray(faces).tolist())):
            ellipse((cx - cr, cy - cr, cx + cr, cy + cr), fill=f, outline=outline, width=ew)

    def segments(self, segs, colour="black", width=1.0):
        """Line segments, an (n, 2, 2) array [segment, end, xy] in data units."""
        segs = np.asarray(segs, float)
        if not len(segs):
            return
        xs, ys = self.x_px(segs[..., 0]), self.y_px(segs[..., 1])
        c, w = rgb(colour), self._width(width)
        line = self.draw.line
        for (a, b), (p, q) in zip(xs.tolist(), ys.tolist()):
            line((a, p, b, q), fill=c, width=w)

    def fill_between(self, x, y1, y2, colour):
        """The region between two curves over x (one polygon; a colour with its alpha blended)."""
        x, y1, y2 = (np.asarray(v, float) for v in (x, y1, y2))
        if len(x) < 2:
            return
        px = self.x_px(np.concatenate([x, x[::-1]]))
        py = self.y_px(np.concatenate([y1, y2[::-1]]))
        self.draw.polygon(list(zip(px.tolist(), py.tolist())), fill=rgb(colour))

    def hline(self, y, colour="black", width=0.8, style="-"):
        self.line(self.xlim, [y, y], colour, width, style)

    def vline(self, x, colour="black", width=0.8, style="-"):
        self.line([x, x], self.ylim, colour, width, style)

    def hspan(self, y0, y1, colour):
        """A band across the box between y0 and y1."""
        a, b = sorted(self.y_px([y0, y1]).tolist())
        self.draw.rectangle([0, a, self.W, b], fill=rgb(colour))

    def cells(self, x_edges, y_edges, colours):
        """Rectangular cells (pcolormesh): colours (ny, nx, 3) between the sorted edges; each
        pixel takes the colour of the cell its centre lies in (none outside). Cells are sharp
        edged: they are looked up at figure pixels and scaled up (NEAREST), 4 x fewer look-ups."""
        cx = np.searchsorted(np.asarray(x_edges, float), self._data_x(np.arange(self.w) + 0.5)) - 1
        cy = np.searchsorted(np.asarray(y_edges, float), self._data_y(np.arange(self.h) + 0.5)) - 1
        colours = np.asarray(colours, np.uint8)
        okx = (cx >= 0) & (cx < colours.shape[1])
        oky = (cy >= 0) & (cy < colours.shape[0])
        if not okx.any() or not oky.any():
            return
        cols, rows = np.flatnonzero(okx), np.flatnonzero(oky)
        c0, c1, r0, r1 = cols[0], cols[-1] + 1, rows[0], rows[-1] + 1      # cells' pixel range
        block = colours.take(cy[r0:r1].clip(0, colours.shape[0] - 1), axis=0) \
                       .take(cx[c0:c1].clip(0, colours.shape[1] - 1), axis=1)
        image = Image.fromarray(np.ascontiguousarray(block), "RGB")
        image = image.resize(((c1 - c0) * self.ss, (r1 - r0) * self.ss), Image.Resampling.NEAREST)
        inside = (okx[c0:c1].all() and oky[r0:r1].all())
        mask = None
        if not inside:                  # a gap between sorted edges can only be outside: mask it
            m = np.outer(oky[r0:r1], okx[c0:c1]).astype(np.uint8) * 255
            mask = Image.fromarray(m, "L").resize(image.size, Image.Resampling.NEAREST)
        self.image.paste(image, (c0 * self.ss, r0 * self.ss), mask)

    def _data_x(self, px):
        x0, x1 = self.xlim
        return x0 + px / self.w * (x1 - x0)          # px in figure pixels

    def _data_y(self, py):
        y0, y1 = self.ylim
        f = py / self.h if self.invert_y else 1.0 - py / self.h
        return y0 + f * (y1 - y0)

    def text(self, x, y, s, size=8, ha="left", va="bottom", colour="black"):
        """Text at data point (x, y), drawn on the figure."""
        fx, fy = self.figure_px(x, y)
        self.fig.text(float(fx), float(fy), s, size=size, ha=ha, va=va, colour=colour)

    def grid(self, colour=blend((176, 176, 176), 0.4), width=0.8):
        """Grid lines at the ticks (matplotlib's grey b0b0b0 at alpha 0.4, blended on white)."""
        xt = self.xticks if self.xticks is not None else nice_ticks(*self.xlim)
        yt = self.yticks if self.yticks is not None else nice_ticks(*self.ylim)
        w, c = self._width(width), rgb(colour)
        for x in self.x_px(xt):
            self.draw.line([(x, 0), (x, self.H)], fill=c, width=w)
        for y in self.y_px(yt):
            self.draw.line([(0, y), (self.W, y)], fill=c, width=w)

    # legend --------------------------------------------------------------
    def legend(self, items, loc="upper right", size=8, ncol=1, frame=True):
        """A legend, drawn on the figure once the box is pasted (by finish(), or now if it was).

        ``items`` are (label, colour, line style or None, line width [pt], marker or None,
        patch): a line, a marker, or (patch) a filled box. ``loc``: 'upper left', 'upper right',
        'lower left', 'lower right', 'center left' inside the box, or 'above right' (outside,
        over the box's right end, no frame)."""
        self._legend = (items, loc, size, ncol, frame)
        if self.finished:
            self._draw_legend(*self._legend)

    def _draw_legend(self, items, loc, size, ncol, frame):
        """legend() drawn: a column of handles and labels, ncol columns, framed or not."""
        if not items:
            return
        fig = self.fig
        fnt = font(fig.pt(size))
        line_h = text_size(fnt, "Ag")[1]
        handle, gap, pad = fig.pt(size) * 2.0, fig.pt(size) * 0.8, fig.pt(size) * 0.4
        widths = [handle + gap + text_size(fnt, it[0])[0] for it in items]
        nrow = -(-len(items) // ncol)
        col_w = [max(widths[k] for k in range(c * nrow, min((c + 1) * nrow, len(items))))
                 for c in range(ncol)]
        total_w = sum(col_w) + gap * (ncol - 1) + 2 * pad
        total_h = nrow * line_h * 1.15 + 2 * pad
        margin = fig.pt(5)
        if loc == "above right":
            x0, y0, frame = self.box[2] - total_w, self.box[1] - total_h, False
        else:
            vert, horiz = loc.split()
            x0 = self.box[0] + margin if horiz == "left" else self.box[2] - margin - total_w
            y0 = {"upper": self.box[1] + margin, "lower": self.box[3] - margin - total_h,
                  "center": (self.box[1] + self.box[3] - total_h) / 2}[vert]
        draw = fig.draw
        if frame:
            draw.rounded_rectangle([x0, y0, x0 + total_w, y0 + total_h], radius=fig.pt(2),
                                   fill=(255, 255, 255), outline=(204, 204, 204), width=_fig_width(fig, 0.8))
        for k, (label, colour, style, width, marker, patch) in enumerate(items):
            colour = rgb(colour)
            c, row = k // nrow, k % nrow
            x = x0 + pad + sum(col_w[:c]) + gap * c
            y = y0 + pad + (row + 0.5) * line_h * 1.15
            if patch:
                draw.rectangle([x, y - line_h * 0.3, x + handle, y + line_h * 0.3], fill=colour)
            elif style:
                pts = np.array([(x, y), (x + handle, y)])
                w = _fig_width(fig, width)
                pattern = DASHES.get(style)
                pieces = [pts] if pattern is None else dash_segments(pts, [p * w for p in pattern])
                for piece in pieces:
                    draw.line([tuple(p) for p in piece], fill=colour, width=w)
            if marker:
                r = fig.pt(5) / 2
                mx = x + handle / 2
                if marker in ("v", "<", ">"):
                    tri = {"v": [(-1, -1), (1, -1), (0, 1)], "<": [(1, -1), (1, 1), (-1, 0)],
                           ">": [(-1, -1), (-1, 1), (1, 0)]}[marker]
                    draw.polygon([(mx + r * a, y + r * b) for a, b in tri], fill=colour)
                else:
                    draw.ellipse([mx - r, y - r, mx + r, y + r], fill=colour)
            fig.text(x + handle + gap, y, label, size=size, va="center")

    # frame, ticks, labels ------------------------------------------------
    def finish(self, xlabel=None, ylabel=None, title=None, title_size=10, title_loc="center",
               tick_size=10, label_size=10, xticks=None, yticks=None, xtick_labels=True,
               ytick_labels=True, right=False, title_colour="black"):
        """Paste the box into the figure (first axes of an image only), draw its frame, the ticks
        (given, or nice_ticks of the limits) with labels, the axis labels and the title. right:
        the y ticks and label at the right edge (a twin's)."""
        fig = self.fig
        x0, y0, x1, y1 = self.box
        if self.owner:
            fig.image.paste(self.image.reduce(self.ss) if self.ss > 1 else self.image, (x0, y0))
        lw = _fig_width(fig, 0.8)
        if self.owner:
            fig.draw.rectangle([x0, y0, x1, y1], outline=(0, 0, 0), width=lw)
        tick, gap = fig.pt(3.5), fig.pt(3.5)
        label_w = 0.0
        xt = np.asarray(xticks if xticks is not None else (self.xticks if self.xticks is not None
                                                           else nice_ticks(*self.xlim)), float)
        yt = np.asarray(yticks if yticks is not None else (self.yticks if self.yticks is not None
                                                           else nice_ticks(*self.ylim)), float)
        if self.owner and not right:
            for x, text in zip(self.x_px(xt) / self.ss, tick_labels(xt)):
                if -0.5 <= x <= self.w + 0.5:
                    fig.draw.line([(x0 + x, y1), (x0 + x, y1 + tick)], fill=(0, 0, 0), width=lw)
                    if xtick_labels:
                        fig.text(x0 + x, y1 + tick + gap * 0.5, text, size=tick_size, ha="center")
        for y, text in zip(self.y_px(yt) / self.ss, tick_labels(yt)):
            if -0.5 <= y <= self.h + 0.5:
                if right:
                    fig.draw.line([(x1, y0 + y), (x1 + tick, y0 + y)], fill=(0, 0, 0), width=lw)
                    if ytick_labels:
                        fig.text(x1 + tick + gap * 0.5, y0 + y, text, size=tick_size, va="center")
                else:
                    fig.draw.line([(x0 - tick, y0 + y), (x0, y0 + y)], fill=(0, 0, 0), width=lw)
                    if ytick_labels:
                        fig.text(x0 - tick - gap * 0.5, y0 + y, text, size=tick_size, ha="right", va="center")
                if ytick_labels:
                    label_w = max(label_w, fig.text_width(text, tick_size))
        if xlabel:
            fig.text((x0 + x1) / 2, y1 + tick + gap + fig.pt(tick_size) * 1.3, xlabel, size=label_size, ha="center")
        if ylabel:
            if right:
                fig.text(x1 + tick + gap * 1.5 + label_w, (y0 + y1) / 2, ylabel, size=label_size,
                         va="center", rotate=True)
            else:
                fig.text(x0 - tick - gap * 1.5 - label_w, (y0 + y1) / 2, ylabel, size=label_size,
                         ha="right", va="center", rotate=True)
        if title:
            x = {"center": (x0 + x1) / 2, "left": x0}[title_loc]
            fig.text(x, y0 - fig.pt(4), title, size=title_size, ha=title_loc, va="bottom", colour=title_colour)
        self.finished = True
        # the supersampled drawing is in the figure now: let it go, so that the next axes reuse
        # its memory (fresh pages cost more than drawing on them)
        self.image = self.draw = None
        if self._legend is not None:
            self._draw_legend(*self._legend)
