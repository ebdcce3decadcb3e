"""symsphere._strategies: the one registry of the ways to sample at a vertex, and the deprecated spellings."""

import pytest

from symsphere._testing import strategies as S


def test_each_program_takes_the_strategies_its_documentation_lists():
    # written out from docs/reference/renderer.md and docs/reference/mitsuba-plugin.md, not read from the registry
    assert S.words("render") == ("cosine", "orbit", "symmetric", "symmetric_cosine", "uniform")
    assert S.words("plugin") == ("bsdf", "cosine", "symmetric", "symmetric_cosine")
    points = {name: s.render_points for name, s in S.SAMPLING_STRATEGIES.items() if s.render_points}
    interlaced = ("sobol_interlaced2", "sobol_interlaced3")
    assert points == {
        "cosine": ("random",), "orbit": ("random",), "uniform": ("random",),
        "symmetric": ("sobol", "random", *interlaced), "symmetric_cosine": ("sobol", "random", *interlaced),
    }  # fmt: skip
    groups = {name: s.group for name, s in S.SAMPLING_STRATEGIES.items()}
    assert groups == {"bsdf": 1, "cosine": 1, "orbit": 1, "symmetric": 24, "symmetric_cosine": 8, "uniform": 1}
    assert [n for n, s in S.SAMPLING_STRATEGIES.items() if s.takes_method] == ["orbit", "symmetric"]


@pytest.mark.parametrize("sampler", sorted(S.SAMPLER_SPELLINGS))
def test_every_old_name_maps_to_words_the_renderer_takes_and_back(sampler):
    strategy, points, method, message = S.from_sampler(sampler, None)
    assert message.startswith(f"sampler={sampler!r} is deprecated; use strategy={strategy!r}, points={points!r}")
    checked = S.check_words(strategy, points, method, "render")
    assert checked[:2] == (strategy, points)
    assert S.legacy_sampler(*checked) == sampler


def test_defaults_and_refusals():
    assert S.check_words("symmetric", None, None, "render") == ("symmetric", "sobol", "equal_area")
    assert S.check_words("symmetric", None, None, "plugin") == ("symmetric", "random", "equal_area")
    assert S.check_words("orbit", None, "paper1", "render") == ("orbit", "random", "paper1")
    assert S.check_words("cosine", None, None, "render") == ("cosine", "random", None)
    with pytest.raises(ValueError, match=r"'bsdf' is not a valid strategy; use one of \{'cosine', 'orbit'"):
        S.check_words("bsdf", None, None, "render")
    with pytest.raises(ValueError, match="'orbit' is not a valid strategy"):
        S.check_words("orbit", None, None, "plugin")
    with pytest.raises(ValueError, match="points for strategy='cosine' in the renderer; use one of {'random'}"):
        S.check_words("cosine", "sobol", None, "render")
    with pytest.raises(ValueError, match="'method' applies only to the strategies orbit, symmetric"):
        S.check_words("uniform", None, "paper1", "render")
    with pytest.raises(TypeError, match="'method' must be a str or None"):
        S.check_words("symmetric", None, 3, "render")
    with pytest.raises(ValueError, match="'sampler' must be one of"):
        S.from_sampler("orbit", None)  # a new word is not an old name


def test_resolve_warns_only_for_the_old_spelling():
    with pytest.warns(DeprecationWarning, match="sampler='paper2' is deprecated"):
        assert S.resolve("paper2", "symmetric", None, None, "render", 1) == ("orbit", "random", "paper2")
    assert S.resolve(None, "symmetric_cosine", "random", None, "render", 1) == ("symmetric_cosine", "random", None)
    with pytest.raises(ValueError, match="not both"):
        S.resolve("cosine", "uniform", None, None, "render", 1)
