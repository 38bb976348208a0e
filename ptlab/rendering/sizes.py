"""How big a render and its jobs are: ``DEFAULT_SPP`` samples per pixel unless told, in tiles
of ``TILE_SIZE`` x ``TILE_SIZE`` pixels and passes of ``SPP_PER_PASS`` samples per pixel
(``jobs`` cuts the image and the samples so).

Batches of about 2^18 paths are the fastest (docs/performance.md): large enough that
NumPy's per-call overhead vanishes, small enough that memory stays modest: 128 x 128 tiles
of 16 samples per pixel per pass. The pass size is fixed, not
derived from the tile size, so that an image does not depend on its tiles.

(A module of its own, importing nothing, so that the command line can judge a render's
size before it imports NumPy.)
"""

#: Samples per pixel of a render that asks for none (``RenderOptions.spp``).
DEFAULT_SPP = 16
#: Tile edge in pixels.
TILE_SIZE = 128
#: Samples per pixel in each pass (with 128 x 128 tiles, batches of 2^18 paths).
SPP_PER_PASS = 16
