/* The drivetrain's linear state space behind the FMI functions (written by flexshaft, not generated).

   x' = A x + B u, y = C x + D u in the drivetrain's modal coordinates: x = [eta; eta'] (mass-normalised
   modes), u the input torques (N.m), y the outputs (rad, rad/s, N.m). The sizes and matrices come from
   model_data.h and model_data.c, which flexshaft generates for each FMU. SI units throughout. */
#ifndef FLEXSHAFT_DRIVETRAIN_H
#define FLEXSHAFT_DRIVETRAIN_H

#include "model_data.h"

typedef struct {
    double x[FS_NX];             /* the state */
    double u[FS_NU];             /* the inputs, held over a co-simulation step (zero-order hold) */
    double A[FS_NX * FS_NX];     /* A under the chosen damping, row-major */
    double Ad[FS_NX * FS_NX];    /* exp(A h) */
    double Bd[FS_NX * FS_NU];    /* integral of exp(A s) B over one step */
    double h;                    /* the step Ad and Bd belong to, s (0: none yet) */
    double time;                 /* s */
    double initial_speed;        /* rad/s at the driving station (parameter) */
    double damping_scale;        /* multiplies the modal damping (parameter) */
    int damping_variant;         /* 1: per-part damping, 2: system damping (parameter) */
    int dirty;                   /* a parameter changed since fs_setup */
} FsModel;

/* Parameters at their start values, state and inputs zero. */
void fs_defaults(FsModel *m);
/* A from the parameters and x from the initial speed; 0, or -1 on a parameter out of range. */
int fs_setup(FsModel *m);
/* dx = A x + B u */
void fs_derivatives(const FsModel *m, double *dx);
/* One exact zero-order-hold step of h seconds; 0, -1 on h <= 0 or a state that is not finite, -2 out
   of memory. */
int fs_step(FsModel *m, double h);

/* The value references, in one place for both FMI versions (model_data.h numbers them): */
/* the real variable vr (time, an input, output, state, derivative or real parameter) into *value; 0, or
   -1 where no real variable has it. */
int fs_get(const FsModel *m, unsigned vr, double *value);
/* set the input or real parameter vr; 0, -1 where none has it, -2 for a fixed parameter once running. */
int fs_set(FsModel *m, unsigned vr, double value, int running);
/* set damping_variant; 0, -1 out of range (1..FS_NVARIANTS), -2 once running. */
int fs_set_variant(FsModel *m, long long value, int running);

#endif
