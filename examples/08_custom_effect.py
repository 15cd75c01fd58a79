"""Example 8: a user post-processing effect (a GLSL snippet and its uniforms) in an om.gl.PostProcess chain.

python examples/08_custom_effect.py [OUTPUT_FOLDER]
"""

from _common import output_dir, side_by_side

import omnirender as om
from omnirender.demo import demo_scene

GREYSCALE = """uniform float u_amount;   // 0: colour, 1: grey
vec4 effect(vec2 uv) {
    vec4 c = texture(u_input, uv);   // linear light
    return vec4(mix(c.rgb, vec3(luminance(c.rgb)), u_amount), c.a);
}"""


def chain(amount: float) -> om.gl.PostProcess:
    grey = om.gl.CustomEffect("greyscale", GREYSCALE, uniforms={"u_amount": amount})
    return om.gl.PostProcess([om.gl.SSAO(), om.gl.ToneMap("aces", exposure=0.5), grey, om.gl.FXAA()])


if __name__ == "__main__":
    out = output_dir()
    images = [om.render(om.Node("root", [chain(a), demo_scene()]), engine="gl", size=(400, 300)) for a in (0.0, 1.0)]
    side_by_side(images).save(out / "08-custom-effect.png")
    print(f"wrote {out / '08-custom-effect.png'} (left: the chain, right: with the greyscale effect)")
