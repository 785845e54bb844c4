/* instances.h — one ball as the viewer draws it, written by instances.cl
 * straight into an OpenGL vertex buffer (or a plain buffer the host copies
 * into one). Floats whatever the solver's precision; included by the kernel
 * and by the viewer's C++ (the GL attribute layout follows these offsets).
 *   float4 0: x, y, z of the centre (m, lab frame), radius (m)
 *   float4 1: speed (m/s), material index, dissipation power (W: energy the
 *             ball lost in contacts since the solver's last observe(reset),
 *             per second), id */
#ifndef MC_INSTANCES_H
#define MC_INSTANCES_H

#define MC_INSTANCE_FLOATS 8
#define MC_INSTANCE_SPEED 4
#define MC_INSTANCE_MATERIAL 5
#define MC_INSTANCE_DISSIPATION 6
#define MC_INSTANCE_ID 7

#endif /* MC_INSTANCES_H */
