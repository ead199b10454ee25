#include "chasles/collision/proximity.h"
