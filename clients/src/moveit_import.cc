#include "moveit_import.h"
