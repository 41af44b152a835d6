"""Numbers from the seed paper that several tests check against, typed in once."""

# Table 7: the flapping Fourier coefficients (a: sine, b: cosine), harmonics 1-3.
TABLE7 = dict(
    ax1=-7.09e-3, bx1=8.89e-2, ax2=3.09e-2, bx2=2.75e-2, ax3=7.32e-3, bx3=1.83e-2,
    az1=4.02e-2, bz1=-5.64e-2, az2=-5.51e-3, bz2=4.24e-2, az3=1.42e-2, bz3=1.29e-2,
    am1=-3.58e-4, bm1=3.20e-3, am2=-5.15e-4, bm2=2.69e-3, am3=5.44e-4, bm3=8.35e-4,
)
