"""The obstacles drawn from the layer kept between frames (static/js/static_layer.js) look as drawn with the scene:
the demo sweep's strut, half transparent, in front of and behind the hose, from the preset views, the canvas read
back pixel by pixel with the layer and without it."""

import numpy as np

from hoseline.demos.sweep import demo_sweep
from hoseline.studio.session import Session
from test_studio_browser import browser, opened_page, pytestmark  # noqa: F401 (the fixture, the skip mark)

# the canvas as drawn now, with the layer (or without: the obstacles drawn with the scene), as RGBA bytes
CANVAS = """(layered) => {
    const scene = window.studio.scene, kept = scene.layer;
    if (!layered) scene.layer = null;
    scene.render();
    const gl = scene.renderer.getContext(), width = gl.drawingBufferWidth, height = gl.drawingBufferHeight;
    const pixels = new Uint8Array(4 * width * height);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    scene.layer = kept;
    return [width, height, Array.from(pixels)];
}"""


def test_the_obstacles_drawn_from_the_layer_look_as_drawn_with_the_scene(browser, tmp_path):  # noqa: F811
    with opened_page(browser, Session(sweep=demo_sweep(steps_per_degree=0.2)), tmp_path) as (page, errors, _):
        page.wait_for_function("() => window.studio.scene.layer.group.children.length === 1")
        for view in ("iso", "top", "front"):
            page.click(f'[data-view="{view}"]')
            *_, layered = page.evaluate(CANVAS, True)
            *_, direct = page.evaluate(CANVAS, False)
            layered, direct = np.array(layered, dtype=int), np.array(direct, dtype=int)
            difference = np.abs(layered - direct)
            assert np.mean(difference > 4) < 0.002, view  # the same but for rounding in the layer's 8 bits
            strut = page.evaluate("() => window.studio.scene.layer.rectangle")
            assert strut[2] * strut[3] > 1000, view  # and the strut is in the picture
        assert errors == []
