/* FMI 2.0 model exchange and co-simulation for the drivetrain of drivetrain.c (written by flexshaft,
   not generated). Value references (model_data.h): the inputs, the outputs, the states, their
   derivatives, then the parameters initial_speed, damping_scale (Real) and damping_variant
   (Enumeration). Parameters are fixed: they may be set until initialisation ends. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "drivetrain.h"

enum { INSTANTIATED, INITIALISING, RUNNING, TERMINATED, FAILED };

typedef struct {
    FsModel m;
    fmi2CallbackLogger log;
    fmi2ComponentEnvironment env;
    char name[128];
    int state;
} Instance;

/* An error, logged (whatever the debug logging: the FMU says nothing else), and its status. */
static fmi2Status refuse(Instance *c, const char *fmt, unsigned vr)
{
    char text[512];
    if (c->log) {
        snprintf(text, sizeof text, fmt, vr);
        c->log(c->env, c->name, fmi2Error, "logStatusError", "%s", text);
    }
    return fmi2Error;
}

static fmi2Status ready(Instance *c)
{
    if (c->m.dirty && fs_setup(&c->m))
        return refuse(c, "a parameter is out of range (damping_variant 1..%u, damping_scale 0..1e6)",
                      FS_NVARIANTS);
    return fmi2OK;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

/* Nothing is logged but errors, which always are. */
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[])
{
    (void)c, (void)on, (void)n, (void)cats;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean logging)
{
    Instance *c;
    (void)type, (void)location, (void)visible, (void)logging;
    if (guid && strcmp(guid, FS_GUID) != 0) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "this binary was built for GUID %s, not %s", FS_GUID, guid);
        return NULL;
    }
    c = (Instance *)calloc(1, sizeof *c);
    if (!c) return NULL;
    fs_defaults(&c->m);
    c->log = functions ? functions->logger : NULL;
    c->env = functions ? functions->componentEnvironment : NULL;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "flexshaft");
    c->state = INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tol, fmi2Real rel, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop)
{
    (void)tol, (void)rel, (void)stop_defined, (void)stop;
    ((Instance *)c)->m.time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    ((Instance *)c)->state = INITIALISING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Instance *i = (Instance *)c;
    if (ready(i) != fmi2OK) return i->state = FAILED, fmi2Error;
    i->state = RUNNING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ((Instance *)c)->state = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    Instance *i = (Instance *)c;
    fs_defaults(&i->m);
    i->state = INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    Instance *i = (Instance *)c;
    size_t k;
    if (ready(i) != fmi2OK) return fmi2Error;
    for (k = 0; k < n; k++)
        if (fs_get(&i->m, vr[k], &value[k]))
            return refuse(i, "no Real variable has value reference %u", vr[k]);
    return fmi2OK;
}

static fmi2Status set_failed(Instance *i, int status, unsigned vr)
{
    if (status == -2)
        return refuse(i, "value reference %u is a fixed parameter: set it before initialisation ends", vr);
    return refuse(i, "value reference %u is not an input or a parameter", vr);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    Instance *i = (Instance *)c;
    size_t k;
    for (k = 0; k < n; k++) {
        int status = fs_set(&i->m, vr[k], value[k], i->state == RUNNING);
        if (status) return set_failed(i, status, vr[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    Instance *i = (Instance *)c;
    size_t k;
    for (k = 0; k < n; k++) {
        if (vr[k] != FS_VR_VARIANT) return refuse(i, "no Integer variable has value reference %u", vr[k]);
        value[k] = i->m.damping_variant;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer value[])
{
    Instance *i = (Instance *)c;
    size_t k;
    for (k = 0; k < n; k++) {
        int status = vr[k] == FS_VR_VARIANT ? fs_set_variant(&i->m, value[k], i->state == RUNNING) : -3;
        if (status == -3) return refuse(i, "no Integer variable has value reference %u", vr[k]);
        if (status == -1)
            return refuse(i, "damping_variant is 1 (parts) or 2 (system), not %u", (unsigned)value[k]);
        if (status) return set_failed(i, status, vr[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    (void)value;
    return n ? refuse((Instance *)c, "no Boolean variable has value reference %u", vr[0]) : fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean value[])
{
    (void)value;
    return n ? refuse((Instance *)c, "no Boolean variable has value reference %u", vr[0]) : fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String value[])
{
    (void)value;
    return n ? refuse((Instance *)c, "no String variable has value reference %u", vr[0]) : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
{
    (void)value;
    return n ? refuse((Instance *)c, "no String variable has value reference %u", vr[0]) : fmi2OK;
}

/* No FMU state snapshots and no directional derivatives (the model description says so). */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c, (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c, (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c, (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n)
{
    (void)c, (void)s, (void)n;
    return fmi2Error;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
{
    (void)c, (void)s, (void)b, (void)n;
    return fmi2Error;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
{
    (void)c, (void)b, (void)n, (void)s;
    return fmi2Error;
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dv[],
                                        fmi2Real dz[])
{
    (void)c, (void)u, (void)nu, (void)z, (void)nz, (void)dv, (void)dz;
    return fmi2Error;
}

/* Model exchange: the continuous state space, no events. */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    (void)c;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean point, fmi2Boolean *event,
                                       fmi2Boolean *stop)
{
    (void)c, (void)point;
    *event = fmi2False;
    *stop = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t)
{
    ((Instance *)c)->m.time = t;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "set all %u states at once", FS_NX);
    if (ready(i) != fmi2OK) return fmi2Error;
    memcpy(i->m.x, x, sizeof i->m.x);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "get all %u derivatives at once", FS_NX);
    if (ready(i) != fmi2OK) return fmi2Error;
    fs_derivatives(&i->m, dx);
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n)
{
    (void)c, (void)z;
    return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n)
{
    Instance *i = (Instance *)c;
    if (n != FS_NX) return refuse(i, "get all %u states at once", FS_NX);
    if (ready(i) != fmi2OK) return fmi2Error;
    memcpy(x, i->m.x, sizeof i->m.x);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n)
{
    size_t k;
    (void)c;
    for (k = 0; k < n; k++) x[k] = 1.0;
    return fmi2OK;
}

/* Co-simulation: one exact zero-order-hold step per communication step. */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)order, (void)value;
    return n ? refuse((Instance *)c, "inputs are held over a step (no input derivatives)", 0) : fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)order, (void)value;
    return n ? refuse((Instance *)c, "no output derivatives", 0) : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior)
{
    Instance *i = (Instance *)c;
    int status;
    (void)no_set_prior;
    if (ready(i) != fmi2OK) return fmi2Error;
    status = fs_step(&i->m, h);
    if (status == -2) return refuse(i, "out of memory for the step's matrices (%u states)", FS_NX);
    if (status) return i->state = FAILED, refuse(i, "no step: the step must be positive and the state "
                                                  "stay finite (%u states)", FS_NX);
    i->m.time = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)c, (void)s;
    *value = fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    (void)s;
    *value = ((Instance *)c)->m.time;
    return s == fmi2LastSuccessfulTime ? fmi2OK : fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)c, (void)s;
    *value = fmi2False;
    return s == fmi2Terminated ? fmi2OK : fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}
