/* _fc_stream: Estimator.stream()'s per-sample step as a compiled entry point (CPython's stable
 * ABI, Python >= 3.10).
 *
 * The twin is the one the cffi binding loaded (fusion_core.native): this module holds only the
 * addresses of a twin's step function, of the twin and of its last estimate, and calls the
 * step with the sample's six numbers and dt as the binding would, without libffi's generic
 * argument conversion; it builds the Estimate (a tuple subclass) through tuple.__new__. No
 * floating-point arithmetic happens here, so the results are the twin's to the bit. A sample
 * that is not six numbers, or that the twin rejects, goes to the `reject` callback (Python:
 * it says why and raises InvalidSample). Built by fusion_core.native.library.build_stream. */
#define Py_LIMITED_API 0x030A0000
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

typedef int (*step_fn)(void *twin, const double acc[3], const double gyro[3], double dt,
                       void *out);

typedef struct {
    PyObject_HEAD
    step_fn step;
    void *twin;
    const double *last; /* the twin's fc_estimate: roll, pitch, bias[3], pos[3], vel[3] */
    int position;
    PyObject *estimate_type; /* fusion_core.types.Estimate */
    PyObject *tuple_new;     /* tuple.__new__ */
    PyObject *reject;        /* reject(acc, gyro, dt): raises InvalidSample */
    PyObject *owner;         /* what keeps the twin's memory alive (its cffi object) */
} Stepper;

static int three(PyObject *seq, double out[3])
{
    if (PyList_Check(seq) || PyTuple_Check(seq)) {
        int list = PyList_Check(seq);
        if ((list ? PyList_Size(seq) : PyTuple_Size(seq)) != 3) {
            return -1;
        }
        for (Py_ssize_t i = 0; i < 3; i++) {
            PyObject *item = list ? PyList_GetItem(seq, i) : PyTuple_GetItem(seq, i);
            if (!PyFloat_Check(item) && !PyLong_Check(item)) {
                return -1;
            }
            out[i] = PyFloat_AsDouble(item);
            if (out[i] == -1.0 && PyErr_Occurred()) {
                PyErr_Clear();
                return -1;
            }
        }
        return 0;
    }
    return -1; /* numpy arrays and other sequences: the Python path converts them */
}

static PyObject *floats(const double *v, Py_ssize_t n)
{
    PyObject *t = PyTuple_New(n);
    if (t == NULL) {
        return NULL;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *x = PyFloat_FromDouble(v[i]);
        if (x == NULL) {
            Py_DECREF(t);
            return NULL;
        }
        PyTuple_SetItem(t, i, x);
    }
    return t;
}

static PyObject *stepper_step(PyObject *self_obj, PyObject *const *args, Py_ssize_t nargs)
{
    Stepper *self = (Stepper *)self_obj;
    double acc[3], gyro[3], dt;
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "step(acc, gyro, dt) takes three arguments");
        return NULL;
    }
    dt = PyFloat_Check(args[2]) || PyLong_Check(args[2]) ? PyFloat_AsDouble(args[2]) : -1.0;
    if (PyErr_Occurred()) {
        PyErr_Clear();
        dt = -1.0;
    }
    if (three(args[0], acc) != 0 || three(args[1], gyro) != 0 || dt == -1.0 ||
        self->step(self->twin, acc, gyro, dt, NULL) > 1 /* FC_SKIPPED */) {
        return PyObject_CallFunctionObjArgs(self->reject, args[0], args[1], args[2], NULL);
    }
    const double *e = self->last;
    PyObject *bias = floats(e + 2, 3), *items = NULL, *result = NULL;
    if (bias == NULL) {
        return NULL;
    }
    PyObject *pos = NULL, *vel = NULL;
    if (self->position) {
        pos = floats(e + 5, 3);
        vel = floats(e + 8, 3);
    } else {
        pos = Py_None;
        vel = Py_None;
        Py_INCREF(pos);
        Py_INCREF(vel);
    }
    PyObject *roll = PyFloat_FromDouble(e[0]), *pitch = PyFloat_FromDouble(e[1]);
    if (pos != NULL && vel != NULL && roll != NULL && pitch != NULL) {
        items = PyTuple_Pack(5, roll, pitch, bias, pos, vel);
    }
    Py_XDECREF(roll);
    Py_XDECREF(pitch);
    Py_DECREF(bias);
    Py_XDECREF(pos);
    Py_XDECREF(vel);
    if (items != NULL) {
        result = PyObject_CallFunctionObjArgs(self->tuple_new, self->estimate_type, items, NULL);
        Py_DECREF(items);
    }
    return result;
}

static PyMethodDef stepper_methods[] = {
    {"step", (PyCFunction)(void (*)(void))stepper_step, METH_FASTCALL,
     "step(acc, gyro, dt): the twin's step of one sample, its Estimate"},
    {NULL, NULL, 0, NULL},
};

/* The stepper takes part in the garbage collector: its `reject` callback holds the stream,
 * which holds the stepper, and the collector breaks that cycle. */
static int stepper_traverse(PyObject *self_obj, visitproc visit, void *arg)
{
    Stepper *self = (Stepper *)self_obj;
    Py_VISIT(self->estimate_type);
    Py_VISIT(self->tuple_new);
    Py_VISIT(self->reject);
    Py_VISIT(self->owner);
    Py_VISIT(Py_TYPE(self_obj));
    return 0;
}

static int stepper_clear(PyObject *self_obj)
{
    Stepper *self = (Stepper *)self_obj;
    Py_CLEAR(self->estimate_type);
    Py_CLEAR(self->tuple_new);
    Py_CLEAR(self->reject);
    Py_CLEAR(self->owner);
    return 0;
}

static void stepper_dealloc(PyObject *self_obj)
{
    PyObject_GC_UnTrack(self_obj);
    stepper_clear(self_obj);
    PyTypeObject *type = Py_TYPE(self_obj);
    freefunc free_fn = (freefunc)PyType_GetSlot(type, Py_tp_free);
    free_fn(self_obj);
    Py_DECREF(type);
}

static PyType_Slot stepper_slots[] = {
    {Py_tp_methods, stepper_methods},
    {Py_tp_dealloc, stepper_dealloc},
    {Py_tp_traverse, stepper_traverse},
    {Py_tp_clear, stepper_clear},
    {Py_tp_doc, "A twin's compiled per-sample step (fusion_core.native.stream)."},
    {0, NULL},
};

static PyType_Spec stepper_spec = {
    "_fc_stream.Stepper", sizeof(Stepper), 0, Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    stepper_slots,
};

static PyObject *stepper_type;

/* stepper(step_address, twin_address, last_address, position, Estimate, tuple_new, reject,
 *         owner): owner keeps the twin's memory alive as long as this stepper lives */
static PyObject *make_stepper(PyObject *module, PyObject *args)
{
    unsigned long long step, twin, last;
    int position;
    PyObject *estimate_type, *tuple_new, *reject, *owner;
    (void)module;
    if (!PyArg_ParseTuple(args, "KKKpOOOO", &step, &twin, &last, &position, &estimate_type,
                          &tuple_new, &reject, &owner)) {
        return NULL;
    }
    if (step == 0 || twin == 0 || last == 0) {
        PyErr_SetString(PyExc_ValueError, "stepper(): an address is 0");
        return NULL;
    }
    PyTypeObject *type = (PyTypeObject *)stepper_type;
    allocfunc alloc = (allocfunc)PyType_GetSlot(type, Py_tp_alloc);
    Stepper *self = (Stepper *)alloc(type, 0);
    if (self == NULL) {
        return NULL;
    }
    self->step = (step_fn)(uintptr_t)step;
    self->twin = (void *)(uintptr_t)twin;
    self->last = (const double *)(uintptr_t)last;
    self->position = position;
    Py_INCREF(estimate_type);
    Py_INCREF(tuple_new);
    Py_INCREF(reject);
    Py_INCREF(owner);
    self->estimate_type = estimate_type;
    self->tuple_new = tuple_new;
    self->reject = reject;
    self->owner = owner; /* (tp_alloc has put it in the collector's care) */
    return (PyObject *)self;
}

static PyMethodDef module_methods[] = {
    {"stepper", make_stepper, METH_VARARGS,
     "stepper(step_address, twin_address, last_address, position, Estimate, tuple_new, "
     "reject, owner)"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_fc_stream", "Estimator.stream()'s compiled per-sample step.", -1,
    module_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__fc_stream(void)
{
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL) {
        return NULL;
    }
    stepper_type = PyType_FromSpec(&stepper_spec);
    if (stepper_type == NULL) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
