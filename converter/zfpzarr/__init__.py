"""zfpzarr: volumes of any size into a multiscale Zarr v3 store of zfp chunks (OME-Zarr 0.5), on Dask."""
from .convert import Options, Summary, convert
from .inputs import InputError, open_input

__all__ = ["Options", "Summary", "convert", "InputError", "open_input"]
__version__ = "0.1.0"
