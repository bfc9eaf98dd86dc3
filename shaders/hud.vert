#version 330 core
// Overlay geometry in framebuffer pixels, origin at the top left, to clip space.
layout(location = 0) in vec2 position;
uniform vec2 screen;

void main()
{
    gl_Position = vec4(2.0 * position.x / screen.x - 1.0, 1.0 - 2.0 * position.y / screen.y, 0.0, 1.0);
}
