#version 330 core
// One triangle covering the viewport, made from gl_VertexID alone (no vertex buffer):
// ids 0, 1, 2 -> (-1,-1), (3,-1), (-1,3). uv runs over the image with v = 0 at its top row.
out vec2 uv;

void main()
{
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    uv = vec2(0.5 + 0.5 * p.x, 0.5 - 0.5 * p.y);
    gl_Position = vec4(p, 0.0, 1.0);
}
