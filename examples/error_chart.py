"""Error against time of three estimators on the sphere on a plane, charted with matplotlib into a
PNG: uniform sphere sampling and cosine sampling with plain random numbers, and cosine sampling with
Owen-scrambled Sobol points, each against the exact image (aoview.exact), one sample a pass,
without adaptive sampling, on the same threads.

    PYTHONPATH=build/python /usr/bin/python3 examples/error_chart.py [-o error-chart.png]"""
import argparse
import os

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the back end)

import aoview  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
METHODS = [('uniform', dict(sampling='uniform', sampler='random')),
           ('cosine', dict(sampling='cosine', sampler='random')),
           ('cosine + Sobol', dict(sampling='cosine', sampler='sobol'))]


def curve(scene, reference, seconds, **settings):
    """(seconds, RMSE) after each pass until `seconds` of render time or 4096 spp."""
    points = []
    for p in aoview.passes(scene, size=(160, 120), spp=4096, spppp=1, adaptive=False, reference=reference,
                           time=seconds, **settings):
        points.append((p.seconds, p.rmse))
    return points


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('-o', '--output', default='error-chart.png')
    parser.add_argument('--seconds', type=float, default=2.0, help='render time of each method')
    args = parser.parse_args()
    scene = aoview.Scene.load(os.path.join(HERE, '..', 'assets', 'scenes', 'sphere-on-plane.scene'))
    reference = aoview.exact(scene, size=(160, 120), spp=4096)
    figure, ax = plt.subplots(figsize=(6, 4.2))
    for name, settings in METHODS:
        points = curve(scene, reference, args.seconds, **settings)
        ax.loglog([s for s, _ in points], [e for _, e in points], label=name)
        print(f'{name}: RMSE {points[-1][1]:.4f} after {points[-1][0]:.2f} s ({len(points)} spp)')
    ax.set_xlabel('render time (s)')
    ax.set_ylabel('RMSE against the exact image')
    ax.set_title('sphere on a plane, 160x120, one sample a pass')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend()
    figure.tight_layout()
    figure.savefig(args.output, dpi=100)
    print(f'wrote {args.output}')


if __name__ == '__main__':
    main()
