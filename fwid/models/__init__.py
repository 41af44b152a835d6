from ._delfly import (
    TABLE1 as TABLE1,
    TABLE4 as TABLE4,
    heading_rate as heading_rate,
    lateral as lateral,
    longitudinal as longitudinal,
)
from ._greybox import GreyBoxModel as GreyBoxModel, Params as Params
