# %% [markdown]
# # symsphere in ten cells
#
# A notebook-style walkthrough (cells marked `# %%`, as Jupytext, VS Code and Spyder read them):
# run it as a script (`python examples/walkthrough.py`), or open it as a notebook
# (`jupytext --to notebook examples/walkthrough.py`).  The test suite runs it
# (tests/test_examples.py), so every line here works.  In Jupyter the results of
# `integrate`, `chi2_test` and `render` display as tables and an image.

# %%
import numpy as np

import symsphere as ss

print("symsphere", ss.__version__)

# %% [markdown]
# ## 1. Directions, 48 at a time
# Rows 48 i ... 48 i + 47 are the orbit of one point of the fundamental triangle T0.

# %%
d = ss.sample_sphere(48 * 1000, rng=1)
print(d.shape, np.allclose(np.linalg.norm(d, axis=1), 1.0), np.allclose(d[:48].mean(axis=0), 0.0))

# %% [markdown]
# ## 2. Any size
# Like `Generator.random(size)`: whole orbits first, the last one cut short; every row is uniform.

# %%
e = ss.sample_sphere(1000, rng=1)  # 20 whole orbits and 40 rows of a 21st
print(e.shape, np.array_equal(e[:960], d[:960]))
h = ss.sample_hemisphere(10, normal=[0, 1, 0], rng=2)
print(h.shape, bool(np.all(h[:, 1] >= 0)))

# %% [markdown]
# ## 3. The scheme as a warp of your own (u, v)
# `square_to_sphere` sends the strip k/48 <= u < (k+1)/48 onto the k-th triangle: a bijection of the square.

# %%
uv = np.random.default_rng(3).random((5, 2))
w = ss.square_to_sphere(uv)
print(np.allclose(ss.sphere_to_square(w), uv), ss.square_to_sphere_pdf(w) * 4 * np.pi)

# %% [markdown]
# ## 4. Integration with an honest error bar

# %%
result = ss.integrate(lambda x: np.exp(x[:, 0]), n=48 * 1024, points="sobol", rng=4)
print(result)
print("exact", 2 * np.pi * (np.e - 1 / np.e))
result  # in Jupyter: a table  # noqa: B018

# %% [markdown]
# ## 5. Is it uniform?  A chi-square test on one direction per orbit (the 48 of an orbit are dependent)

# %%
test = ss.stats.chi2_test(ss.stats.one_per_orbit(d, 48, rng=5), ss.stats.uniform_pdf("sphere"), "sphere")
print(test.passed, round(test.p_value, 3))
test  # in Jupyter: a table  # noqa: B018

# %% [markdown]
# ## 6. The paper's maps: not uniform, but unbiased with their density

# %%
p = ss.sample_sphere(48 * 10_000, method="paper1", rng=6)
print(np.mean(np.exp(p[:, 0]) / ss.sphere_pdf(p, "paper1")), "vs", 2 * np.pi * (np.e - 1 / np.e))

# %% [markdown]
# ## 7. A small render (`ss.render` loads on first use)

# %%
image = ss.render.render("cornell", width=32, height=24, spp=24, seed=7, progress=False)
print(image.image.shape, f"{image.paths} paths")
image  # in Jupyter: the picture  # noqa: B018
