"""The progressive display of the course's base code, with aoview doing the tracing: a pass loop
that shows the running average as it converges (a matplotlib window where there is a display),
and saves a strip of the passes it showed into a PNG.

    PYTHONPATH=build/python /usr/bin/python3 examples/progressive.py [SCENE] [-o progressive.png]

progressive_render_display(jitter, total_spp, spppp, sampling_type) of the base code becomes
aoview.progressive(scene, jitter, total_spp, spppp, sampling_type): ceil(total_spp / spppp) passes
of spppp samples per pixel, as the base code's."""
import argparse
import os

import matplotlib
import numpy as np

import aoview

if not os.environ.get('DISPLAY'):
    matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the back end)

HERE = os.path.dirname(os.path.abspath(__file__))


def progressive_render_display(scene, jitter=True, total_spp=256, spppp=8, sampling_type='cosine',
                               size=(320, 240), shown=6):
    """Renders pass after pass, drawing each running average (when interactive), and returns the
    images of about `shown` passes spread over the run with their captions."""
    interactive = matplotlib.get_backend().lower() != 'agg'
    if interactive:
        plt.ion()
        figure, axes = plt.subplots()
        picture = axes.imshow(np.zeros(size[::-1]), cmap='gray', vmin=0, vmax=1)
    kept = []
    passes = -(-total_spp // spppp)
    keep = set(np.unique(np.geomspace(1, passes, shown).round().astype(int)))
    for p in aoview.progressive(scene, jitter, total_spp, spppp, sampling_type, size=size):
        caption = f'pass {p.number}: {p.mean_spp:.0f} of {p.target_spp} spp, {p.seconds:.2f} s'
        if interactive:
            picture.set_data(p.image)
            axes.set_title(caption)
            plt.pause(0.001)
        if p.number in keep:
            kept.append((p.image, caption))
    return kept


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('scene', nargs='?', default=os.path.join(HERE, '..', 'assets', 'scenes', 'spheres.scene'))
    parser.add_argument('-o', '--output', default='progressive.png')
    parser.add_argument('--sampling', default='uniform', choices=['uniform', 'hemisphere', 'cosine'])
    args = parser.parse_args()
    scene = aoview.Scene.load(args.scene)
    kept = progressive_render_display(scene, total_spp=256, spppp=8, sampling_type=args.sampling)
    figure, axes = plt.subplots(1, len(kept), figsize=(3 * len(kept), 2.6))
    for ax, (image, caption) in zip(np.atleast_1d(axes), kept):
        # sRGB-encoded as aoview's window shows it (docs/contract.md: PNG is the sRGB running average).
        shown = np.where(image <= 0.0031308, 12.92 * image, 1.055 * np.power(np.clip(image, 0, 1), 1 / 2.4) - 0.055)
        ax.imshow(np.clip(shown, 0, 1), cmap='gray', vmin=0, vmax=1)
        ax.set_title(caption, fontsize=9)
        ax.axis('off')
    figure.suptitle(f'{scene.name}: {args.sampling} sampling, 8 samples per pixel a pass')
    figure.tight_layout()
    figure.savefig(args.output, dpi=100)
    print(f'wrote {args.output}')


if __name__ == '__main__':
    main()
