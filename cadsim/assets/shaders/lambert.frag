#version 330 core
// cadsim: Lambertian replacement for pyrender's PBR mesh.frag (same inputs and uniform names).
// Diffuse sun + ambient, per-vertex colour (linear RGB), gamma-encoded output. About 3x cheaper
// per fragment than the PBR shader on llvmpipe; see docs/rendering.md.

struct DirectionalLight {
    vec3 color;
    float intensity;
    vec3 direction;
};

struct Material {
    vec4 base_color_factor;
};

uniform Material material;
uniform DirectionalLight directional_lights[MAX_DIRECTIONAL_LIGHTS];
uniform int n_directional_lights;
uniform vec3 ambient_light;

in vec3 frag_position;
#ifdef NORMAL_LOC
in vec3 frag_normal;
#endif
#ifdef COLOR_0_LOC
in vec4 color_multiplier;
#endif

out vec4 frag_color;

void main()
{
    vec3 base = material.base_color_factor.rgb;
#ifdef COLOR_0_LOC
    base *= color_multiplier.rgb;
#endif
    vec3 light = ambient_light;
#ifdef NORMAL_LOC
    vec3 n = normalize(frag_normal);
    for (int i = 0; i < n_directional_lights; i++) {
        float nl = max(dot(n, -directional_lights[i].direction), 0.0);
        light += directional_lights[i].color * directional_lights[i].intensity * nl;
    }
#endif
    frag_color = vec4(pow(clamp(base * light, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
