/* The floor for aoview's start-up (tests/bench/bench_startup.sh): a program linked to Embree alone that
 * creates and releases a device, which loads Embree, TBB and the C++ runtime as aoview does. */
#include <stdio.h>

#include <embree3/rtcore.h>

int main(void)
{
    RTCDevice device = rtcNewDevice(NULL);
    if (!device) {
        fprintf(stderr, "bench_embree_start: rtcNewDevice failed\n");
        return 1;
    }
    rtcReleaseDevice(device);
    return 0;
}
