"""Synthetic BOS pairs for the tests: a smoothed random texture and the same
texture shifted by a sub-pixel displacement (Fourier shift), written as
binary PGM files that OpenCV reads."""
import numpy as np


def texture(rows, cols, seed=1):
    rng = np.random.default_rng(seed)
    noise = rng.random((rows, cols))
    spectrum = np.fft.fft2(noise)
    fy = np.fft.fftfreq(rows)[:, None]
    fx = np.fft.fftfreq(cols)[None, :]
    spectrum *= np.exp(-(fx ** 2 + fy ** 2) * (2 * np.pi * 0.7) ** 2 / 2)  # Gaussian blur, σ 0.7 px
    return spectrum


def pair(rows=128, cols=160, shift=(0.4, -0.7), seed=1):
    """(reference, measurement) as uint8 arrays; the measurement is the
    reference moved by shift = (u, v) px."""
    spectrum = texture(rows, cols, seed)
    fy = np.fft.fftfreq(rows)[:, None]
    fx = np.fft.fftfreq(cols)[None, :]
    moved = spectrum * np.exp(-2j * np.pi * (fx * shift[0] + fy * shift[1]))
    images = []
    for s in (spectrum, moved):
        img = np.real(np.fft.ifft2(s))
        img = (img - img.mean()) / img.std() * 40 + 128
        images.append(np.ascontiguousarray(np.clip(np.rint(img), 0, 255), dtype=np.uint8))
    return images[0], images[1]


def write_pgm(path, image):
    rows, cols = image.shape
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (cols, rows))
        f.write(np.ascontiguousarray(image, dtype=np.uint8).tobytes())
