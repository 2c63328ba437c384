uniform int u_verlet;
uniform float u_dt;

flat in vec3 v_position;
flat in vec3 v_velocity;
flat in vec4 v_attributes;

layout(location = 0) out vec4 out_state0;
layout(location = 1) out vec4 out_state1;
layout(location = 2) out vec4 out_attributes;

void main() {
  out_state0 = vec4(v_position, 1.0);
  // Verlet keeps no velocity: the birth velocity becomes the previous position.
  out_state1 = u_verlet == 0 ? vec4(v_velocity, 0.0) : vec4(v_position - v_velocity * u_dt, 1.0);
  out_attributes = v_attributes;
}
