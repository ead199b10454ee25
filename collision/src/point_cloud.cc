#include "chasles/collision/scene.h"
