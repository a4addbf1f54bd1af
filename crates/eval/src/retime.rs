//! Time warping: resampling, speed, warp curves and reversal, baked to linear keys.
