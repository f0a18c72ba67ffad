"""PNG files written without PIL's filter search: png_bytes(pixels, dpi), the encoder of the
pixels that matplotlib's Agg draws for compare/figures/runs.py."""

import struct
import zlib

import numpy as np

# The pictures' resolution (dots per inch) and the zlib level of their pixels.
SAVE_DPI = 150
PNG_COMPRESS_LEVEL = 3


def _png_chunk(kind, data):
    """One PNG chunk: length, type, data, CRC of type and data."""
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(data, zlib.crc32(kind)))


def png_bytes(pixels, dpi):
    """A PNG file of an (h, w, 3) RGB or (h, w, 4) RGBA uint8 array, with its dpi (pHYs).

    Every row is stored unfiltered (filter type 0) and deflated at zlib level PNG_COMPRESS_LEVEL:
    a figure's flat colours compress as well as with PIL's adaptive row filters (frames.png
    1.34 against 1.57 MB), in half PIL's time, whose filtering costs as much as the deflate."""
    h, w, channels = pixels.shape
    return png_bytes_of_rows(w, h, channels, lambda y0, y1: pixels[y0:y1], dpi)


# Rows a strip: the rows with their filter bytes are made a strip at a time (some 100 kB for a
# 1500-pixel-wide picture) rather than as one copy of the whole picture.
STRIP_ROWS = 64


def png_bytes_of_rows(w, h, channels, rows_of, dpi):
    """png_bytes of a w x h picture whose rows y0 <= y < y1 rows_of(y0, y1) gives as an
    (y1 - y0, w, channels) uint8 array: deflated a strip of STRIP_ROWS at a time, the same bytes
    as the whole picture at once (one zlib stream, fed in order)."""
    strip = np.zeros((STRIP_ROWS, 1 + w * channels), np.uint8)   # each row: filter byte 0, then its pixels
    deflate = zlib.compressobj(PNG_COMPRESS_LEVEL)
    data = []
    for y0 in range(0, h, STRIP_ROWS):
        n = min(STRIP_ROWS, h - y0)
        strip[:n, 1:].reshape(n, w, channels)[...] = rows_of(y0, y0 + n)
        data.append(deflate.compress(strip[:n].data))
    data.append(deflate.flush())
    ppm = int(dpi / 0.0254 + 0.5)                      # pixels per metre, as PIL writes them
    return b"".join([b"\x89PNG\r\n\x1a\n",
                     _png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2 if channels == 3 else 6, 0, 0, 0)),
                     _png_chunk(b"pHYs", struct.pack(">IIB", ppm, ppm, 1)),
                     _png_chunk(b"IDAT", b"".join(data)),
                     _png_chunk(b"IEND", b"")])
