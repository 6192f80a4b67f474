/* FMI 3.0 model exchange and co-simulation for the drivetrain of drivetrain.c (written by flexshaft,
   not generated). Value references (model_data.h): the inputs, the outputs, the states, their
   derivatives, then the parameters initial_speed, damping_scale (Float64) and damping_variant
   (an Enumeration, read and set as Int64). Parameters are fixed: they may be set until
   initialisation ends. No clocks, no scheduled execution, no FMU state snapshots. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "drivetrain.h"

enum { INSTANTIATED, INITIALISING, RUNNING, TERMINATED, FAILED };

typedef struct {
    FsModel m;
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
    int state;
} Instance;

/* An error, logged (whatever the debug logging: the FMU says nothing else), and its status. */
static fmi3Status refuse(Instance *c, const char *fmt, unsigned vr)
{
    char text[512];
    if (!c->log) return fmi3Error;
    snprintf(text, sizeof text, fmt, vr);
    c->log(c->env, fmi3Error, "logStatusError", text);
    return fmi3Error;
}

static fmi3Status ready(Instance *c)
{
    if (c->m.dirty && fs_setup(&c->m))
        return refuse(c, "a parameter is out of range (damping_variant 1..%u, damping_scale 0..1e6)",
                      FS_NVARIANTS);
    return fmi3OK;
}

static Instance *create(fmi3String token, fmi3InstanceEnvironment env, fmi3LogMessageCallback log)
{
    Instance *c;
    if (token && strcmp(token, FS_GUID) != 0) {
        if (log)
            log(env, fmi3Error, "logStatusError", "this binary was built for another instantiation token");
        return NULL;
    }
    c = (Instance *)calloc(1, sizeof *c);
    if (!c) return NULL;
    fs_defaults(&c->m);
    c->log = log;
    c->env = env;
    c->state = INSTANTIATED;
    return c;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

/* Nothing is logged but errors, which always are. */
fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[])
{
    (void)c, (void)on, (void)n, (void)cats;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                          fmi3Boolean visible, fmi3Boolean logging,
                                          fmi3InstanceEnvironment env, fmi3LogMessageCallback log)
{
    (void)name, (void)resources, (void)visible, (void)logging;
    return create(token, env, log);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean event_mode,
                                         fmi3Boolean early_return, const fmi3ValueReference required[],
                                         size_t n_required, fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update)
{
    (void)name, (void)resources, (void)visible, (void)logging, (void)event_mode, (void)early_return,
        (void)required, (void)n_required, (void)update;
    return create(token, env, log);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
                                               fmi3Boolean visible, fmi3Boolean logging,
                                               fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                               fmi3ClockUpdateCallback clock, fmi3LockPreemptionCallback lock,
                                               fmi3UnlockPreemptionCallback unlock)
{
    (void)name, (void)token, (void)resources, (void)visible, (void)logging, (void)env, (void)log,
        (void)clock, (void)lock, (void)unlock;
    return NULL; /* not offered (the model description does not declare it) */
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tol_defined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop)
{
    Instance *i = (Instance *)c;
    (void)tol_defined, (void)tol, (void)stop_defined, (void)stop;
    i->m.time = start;
    i->state = INITIALISING;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c)
{
    Instance *i = (Instance *)c;
    if (ready(i) != fmi3OK) return i->state = FAILED, fmi3Error;
    i->state = RUNNING;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3Terminate(fmi3Instance c)
{
    ((Instance *)c)->state = TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance c)
{
    Instance *i = (Instance *)c;
    fs_defaults(&i->m);
    i->state = INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 value[],
                          size_t nv)
{
    Instance *i = (Instance *)c;
    size_t k;
    if (nv != n) return refuse(i, "one value per value reference (%u given)", (unsigned)nv);
    if (ready(i) != fmi3OK) return fmi3Error;
    for (k = 0; k < n; k++)
        if (fs_get(&i->m, vr[k], &value[k]))
            return refuse(i, "no Float64 variable has value reference %u", vr[k]);
    return fmi3OK;
}

static fmi3Status set_failed(Instance *i, int status, unsigned vr)
{
    if (status == -2)
        return refuse(i, "value reference %u is a fixed parameter: set it before initialisation ends", vr);
    return refuse(i, "value reference %u is not an input or a parameter", vr);
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                          const fmi3Float64 value[], size_t nv)
{
    Instance *i = (Instance *)c;
    size_t k;
    if (nv != n) return refuse(i, "one value per value reference (%u given)", (unsigned)nv);
    for (k = 0; k < n; k++) {
        int status = fs_set(&i->m, vr[k], value[k], i->state == RUNNING);
        if (status) return set_failed(i, status, vr[k]);
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Int64 value[], size_t nv)
{
    Instance *i = (Instance *)c;
    size_t k;
    if (nv != n) return refuse(i, "one value per value reference (%u given)", (unsigned)nv);
    for (k = 0; k < n; k++) {
        if (vr[k] != FS_VR_VARIANT) return refuse(i, "no Int64 variable has value reference %u", vr[k]);
        value[k] = i->m.damping_variant;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3Int64 value[],
                        size_t nv)
{
    Instance *i = (Instance *)c;
    size_t k;
    if (nv != n) return refuse(i, "one value per value reference (%u given)", (unsigned)nv);
    for (k = 0; k < n; k++) {
        int status = vr[k] == FS_VR_VARIANT ? fs_set_variant(&i->m, value[k], i->state == RUNNING) : -3;
        if (status == -3) return refuse(i, "no Int64 variable has value reference %u", vr[k]);
        if (status == -1)
            return refuse(i, "damping_variant is 1 (parts) or 2 (system), not %u", (unsigned)value[k]);
        if (status) return set_failed(i, status, vr[k]);
    }
    return fmi3OK;
}

/* The types this FMU has no variable of: any value reference is an error. */
#define NO_GET(T, N)                                                                                     \
    fmi3Status fmi3Get##N(fmi3Instance c, const fmi3ValueReference vr[], size_t n, T value[], size_t nv) \
    {                                                                                                    \
        (void)value, (void)nv;                                                                           \
        return n ? refuse((Instance *)c, "no " #N " variable has value reference %u", vr[0]) : fmi3OK;   \
    }
#define NO_SET(T, N)                                                                                     \
    fmi3Status fmi3Set##N(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const T value[],      \
                          size_t nv)                                                                     \
    {                                                                                                    \
        (void)value, (void)nv;                                                                           \
        return n ? refuse((Instance *)c, "no " #N " variable has value reference %u", vr[0]) : fmi3OK;   \
    }
#define NO_TYPE(T, N) NO_GET(T, N) NO_SET(T, N)
NO_TYPE(fmi3Float32, Float32)
NO_TYPE(fmi3Int8, Int8)
NO_TYPE(fmi3UInt8, UInt8)
NO_TYPE(fmi3Int16, Int16)
NO_TYPE(fmi3UInt16, UInt16)
NO_TYPE(fmi3Int32, Int32)
NO_TYPE(fmi3UInt32, UInt32)
NO_TYPE(fmi3UInt64, UInt64)
NO_TYPE(fmi3Boolean, Boolean)
NO_TYPE(fmi3String, String)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t n, size_t sizes[],
                         fmi3Binary value[], size_t nv)
{
    (void)sizes, (void)value, (void)nv;
    return n ? refuse((Instance *)c, "no Binary variable has value reference %u", vr[0]) : fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const size_t sizes[],
                         const fmi3Binary value[], size_t nv)
{
    (void)sizes, (void)value, (void)nv;
    return n ? refuse((Instance *)c, "no Binary variable has value reference %u", vr[0]) : fmi3OK;
}

/* No clocks. */
fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Clock v[])
{
    (void)c, (void)vr, (void)n, (void)v;
    return fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3Clock v[])
{
    (void)c, (void)vr, (void)n, (void)v;
    return fmi3Error;
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 v[],
                                  fmi3IntervalQualifier q[])
{
    (void)c, (void)vr, (void)n, (void)v, (void)q;
    return fmi3Error;
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                   fmi3UInt64 counters[], fmi3UInt64 res[], fmi3IntervalQualifier q[])
{
    (void)c, (void)vr, (void)n, (void)counters, (void)res, (void)q;
    return fmi3Error;
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 v[])
{
    (void)c, (void)vr, (void)n, (void)v;
    return fmi3Error;
}
fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                fmi3UInt64 counters[], fmi3UInt64 res[])
{
    (void)c, (void)vr, (void)n, (void)counters, (void)res;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                  const fmi3Float64 v[])
{
    (void)c, (void)vr, (void)n, (void)v;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                   const fmi3UInt64 counters[], const fmi3UInt64 res[])
{
    (void)c, (void)vr, (void)n, (void)counters, (void)res;
    return fmi3Error;
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3Float64 v[])
{
    (void)c, (void)vr, (void)n, (void)v;
    return fmi3Error;
}
fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                const fmi3UInt64 counters[], const fmi3UInt64 res[])
{
    (void)c, (void)vr, (void)n, (void)counters, (void)res;
    return fmi3Error;
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clock, fmi3Float64 t)
{
    (void)c, (void)clock, (void)t;
    return fmi3Error;
}

/* Dependencies: none declared beyond the model description's; no configuration mode. */
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr, size_t *n)
{
    (void)c, (void)vr, (void)n;
    return fmi3Error;
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent, size_t ed[],
                                       fmi3ValueReference independents[], size_t ei[],
                                       fmi3DependencyKind kinds[], size_t n)
{
    (void)c, (void)dependent, (void)ed, (void)independents, (void)ei, (void)kinds, (void)n;
    return fmi3Error;
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }

/* No FMU state snapshots and no directional or adjoint derivatives (the description says so). */
fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) { (void)c, (void)s; return fmi3Error; }
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) { (void)c, (void)s; return fmi3Error; }
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) { (void)c, (void)s; return fmi3Error; }
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *n)
{
    (void)c, (void)s, (void)n;
    return fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte b[], size_t n)
{
    (void)c, (void)s, (void)b, (void)n;
    return fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte b[], size_t n, fmi3FMUState *s)
{
    (void)c, (void)b, (void)n, (void)s;
    return fmi3Error;
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                        const fmi3ValueReference k[], size_t nk, const fmi3Float64 seed[],
                                        size_t ns, fmi3Float64 sens[], size_t nsens)
{
    (void)c, (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sens, (void)nsens;
    return fmi3Error;
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference u[], size_t nu,
                                    const fmi3ValueReference k[], size_t nk, const fmi3Float64 seed[],
                                    size_t ns, fmi3Float64 sens[], size_t nsens)
{
    (void)c, (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sens, (void)nsens;
    return fmi3Error;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *update, fmi3Boolean *stop,
                                    fmi3Boolean *nominals, fmi3Boolean *values, fmi3Boolean *next_defined,
                                    fmi3Float64 *next)
{
    (void)c;
    *update = fmi3False, *stop = fmi3False, *nominals = fmi3False, *values = fmi3False;
    *next_defined = fmi3False, *next = 0.0;
    return fmi3OK;
}

/* Model exchange: the continuous state space, no events. */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean no_set, fmi3Boolean *event,
                                       fmi3Boolean *stop)
{
    (void)c, (void)no_set;
    *event = fmi3False, *stop = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t)
{
    ((Instance *)c)->m.time = t;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "set all %u states at once", FS_NX);
    if (ready(i) != fmi3OK) return fmi3Error;
    memcpy(i->m.x, x, sizeof i->m.x);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "get all %u derivatives at once", FS_NX);
    if (ready(i) != fmi3OK) return fmi3Error;
    fs_derivatives(&i->m, dx);
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t n)
{
    (void)c, (void)z;
    return n ? fmi3Error : fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "get all %u states at once", FS_NX);
    if (ready(i) != fmi3OK) return fmi3Error;
    memcpy(x, i->m.x, sizeof i->m.x);
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n)
{
    size_t k;
    (void)c;
    for (k = 0; k < n; k++) x[k] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n)
{
    (void)c;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n)
{
    (void)c;
    *n = FS_NX;
    return fmi3OK;
}

/* Co-simulation: one exact zero-order-hold step per communication step. */
fmi3Status fmi3EnterStepMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                    const fmi3Int32 orders[], fmi3Float64 v[], size_t nv)
{
    (void)vr, (void)orders, (void)v, (void)nv;
    return n ? refuse((Instance *)c, "no output derivatives", 0) : fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_set,
                      fmi3Boolean *event, fmi3Boolean *stop, fmi3Boolean *early, fmi3Float64 *last)
{
    Instance *i = (Instance *)c;
    int status;
    (void)no_set;
    *event = fmi3False, *stop = fmi3False, *early = fmi3False, *last = t;
    if (ready(i) != fmi3OK) return fmi3Error;
    status = fs_step(&i->m, h);
    if (status == -2) return refuse(i, "out of memory for the step's matrices (%u states)", FS_NX);
    if (status) return i->state = FAILED, refuse(i, "no step: the step must be positive and the state "
                                                  "stay finite (%u states)", FS_NX);
    i->m.time = t + h;
    *last = t + h;
    return fmi3OK;
}
