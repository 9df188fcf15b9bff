"""Bias and variance of a renderer over seeds, as the study scripts report them
(scripts/psf_study.sh, scripts/restir_study.sh): per pixel, the mean of the seeds' images against
a reference gives the bias, their spread the variance, both weighted as relMSE weighs a pixel."""
import numpy as np


def over_seeds(images, ref):
    """`images`: the seeds' images (arrays of one shape), `ref`: the reference (float64). Returns
    the relative squared bias (the mean's own noise, var / seeds, taken out of its squared distance
    to the reference), the relative variance over seeds, the relMSE of one render, and the image
    mean's relative bias with its standard error over seeds (means over pixels and channels)."""
    w = 1.0 / (ref * ref + 0.01)  # relMSE's weight
    imgs = np.stack(images).astype(np.float64)
    seeds = imgs.shape[0]
    mean = imgs.mean(axis=0)
    var = imgs.var(axis=0, ddof=1) if seeds > 1 else np.zeros_like(mean)
    means = imgs.mean(axis=tuple(range(1, imgs.ndim))) / ref.mean() - 1
    return {
        "bias2": np.mean(w * ((mean - ref) ** 2 - var / seeds)),
        "variance": np.mean(w * var),
        "one": np.mean(w * (imgs - ref) ** 2),
        "image_bias": means.mean(),
        "image_bias_se": means.std(ddof=1) / np.sqrt(seeds) if seeds > 1 else 0.0,
    }
