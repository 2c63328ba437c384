// Opaque goo: diffuse + Fresnel sky rim + specular, depth-tested into the scene.
uniform vec3 u_goo_colour;
in vec3 v_world;
in vec3 v_normal;
layout(location = 0) out vec4 out_colour;
void main() {
  vec3 n = facingNormal(v_normal);
  vec3 to_eye = normalize(u_eye - v_world);
  float diffuse = 0.25 + 0.75 * max(dot(n, u_light), 0.0);
  float f = fresnel(dot(n, to_eye));
  vec3 colour = mix(u_goo_colour * diffuse, sky(reflect(-to_eye, n)), f * 0.5) + vec3(0.6 * specular(n, to_eye));
  out_colour = vec4(colour, 1.0);
}
