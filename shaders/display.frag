#version 330 core
// The running average (linear RGB; texture row 0 is the image's top row) encoded with the sRGB
// curve of image.c's ao_image_srgb_encode and quantised to 8 bits as the PNG is, so that the
// window, the screenshot and the CPU encoding agree.
uniform sampler2D image;
uniform vec2 cover;   // the share of the texture the image covers: below 1 for a preview's cells
in vec2 uv;
out vec4 colour;

float encode(float x)
{
    x = clamp(x, 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

void main()
{
    vec3 linear = texture(image, uv * cover).rgb;
    vec3 srgb = vec3(encode(linear.r), encode(linear.g), encode(linear.b));
    colour = vec4(floor(srgb * 255.0 + 0.5) / 255.0, 1.0);
}
