#version 330 core
// One flat colour per draw: the translucent box, then the text.
uniform vec4 tint;
out vec4 colour;

void main()
{
    colour = tint;
}
